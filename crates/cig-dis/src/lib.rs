//! DIS (IEEE 1278.1-2012, protocol version 7, and 1278.1a-1998, version 6) for cig, pure:
//! no sockets, no clocks — callers pass bytes in and monotonic seconds.
//!
//! Algorithm and sources, per module: [`codec`] walks datagrams by the PDU header and decodes
//! Entity State, Fire, Detonation, Remove Entity, Data Query, Set Data and Data through the
//! `dis-rs` crate and the Environmental Process PDU ([`environmental`], §7.10.5 with the
//! SISO-REF-010 Gaussian plume/puff records) by hand; [`dead_reckoning`] implements DRM 1-9 of
//! Annex E; [`remote`] keeps the remote entity table with smoothing and timeouts;
//! [`publisher`] applies the 1 m / 3° thresholds and 5 s heartbeat to owned entities;
//! [`appearance`] maps appearance bits to obscurant effects (thesis 000 §VI.E.2-3) and to
//! the lights an entity has on (SISO-REF-010 land, air, surface and subsurface layouts);
//! [`detonation`] turns ground and building impacts into seeded effect starts (§VI.E.2);
//! [`time_sync`] shares the simulation world time and lightning (§VI.E.4-5) over Data PDUs;
//! [`object_state`] encodes and decodes the Point and Linear Object State PDUs (§7.10.4-7.10.5,
//! dynamic terrain: craters, fighting positions, ruts, ditches) by hand.
//!
//! Limits: see each module. Nothing here opens a socket or reads a clock; the `cig` binary owns
//! the network edge.

pub mod appearance;
pub mod codec;
pub mod dead_reckoning;
pub mod detonation;
pub mod environmental;
pub mod object_state;
pub mod publisher;
pub mod remote;
pub mod time_sync;

pub use dis_rs;

pub use appearance::{DustCloudSize, EffectsDiff, EffectsRequested, EntityEffect, LightsRequested};
pub use codec::{
    decode_datagram, decode_header, decode_pdu, encode_pdu, DecodeError, DecodedPdu, DisMessage,
    DisVersion, EncodeError, EncodeHeader, PduHeaderInfo,
};
pub use dead_reckoning::{extrapolate, DrAlgorithm, DrInput, DrModel, DrPose, EulerAngles};
pub use detonation::{impact_effect, EventIdentity, ImpactEffectStart, ImpactSize, ImpactSurface};
pub use environmental::{
    EnvironmentGeometry, EnvironmentRecord, EnvironmentalProcess, GaussianPlume, GaussianPuff,
};
pub use object_state::{
    decode_linear_object_state, decode_point_object_state, encode_linear_object_state,
    encode_point_object_state, LinearObjectState, LinearSegment, ObjectId, ObjectStateError,
    ObjectType, PointObjectState, SimulationAddress,
};
pub use publisher::{OwnedEntityPublisher, OwnedEntityState, PublisherConfig, SendReason};
pub use remote::{
    EntityKey, EntityTypeCode, RemoteEntitySnapshot, RemoteEntityTable, RemoteTableConfig,
    TableEvent,
};
pub use time_sync::{LightningStrike, NodeId, TimeMessage, TimeRole, TimeSync, TimeSyncConfig};
