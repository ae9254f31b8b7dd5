//! The terrain database's edge: reading DEM files of the user ([`import`]) and the database
//! directory on disk ([`store`]).

pub mod import;
pub mod store;
