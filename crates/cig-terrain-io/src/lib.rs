//! The terrain database's edge: reading DEM files of the user ([`import`]), road, river and lake
//! feature files ([`features`]) and the culture in them ([`culture`]), and the database
//! directory on disk ([`store`]).

pub mod culture;
pub mod edits;
pub mod features;
pub mod imagery;
pub mod import;
pub mod store;
