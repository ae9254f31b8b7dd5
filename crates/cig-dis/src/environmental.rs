//! Environmental Process PDU (type 41) body codec, with Gaussian Plume and Gaussian Puff records.
//!
//! Algorithm: a straight big-endian field walk over the layout of IEEE 1278.1-2012 §7.10.5
//! (Environmental Process PDU, Synthetic Environment family) and §6.2.31 (Environment record),
//! with the record bodies laid out as SISO-REF-010 records UID 264 (Gaussian Plume) and
//! UID 265 (Gaussian Puff), record type numbers from SISO-REF-010 UID 250
//! (Gaussian Plume 1610612736 = 0x6000_0000, Gaussian Puff 1879048192 = 0x7000_0000).
//!
//! Body layout (octets): Environmental Process ID (site 2, application 2, number 2),
//! Environment Type (entity type record, 8), Model Type (1), Environment Status (1: bit 0
//! "is last", bit 1 "is active"), Number of Environment Records (2), Sequence Number (2), then
//! the records. Each record: Record Type (4), Record Length (2, in bits), Index (1),
//! padding (1), the record-specific fields, zero padding up to a multiple of 8 octets.
//!
//! Gaussian Plume fields (76 octets): source location (3 x f64, ECEF m), orientation
//! (psi, theta, phi: 3 x f32 rad), plume length, width, height (3 x f32 m), their time
//! derivatives (3 x f32 m/s), leading edge centroid height (f32 m), leading edge velocity
//! (3 x f32 m/s). Gaussian Puff fields (112 octets): puff location and origination location
//! (2 x 3 x f64 ECEF m), sigma x, y, z (3 x f32 m), their time derivatives (3 x f32 m/s),
//! orientation (3 x f32 rad), velocity (3 x f32 m/s), angular velocity (3 x f32 rad/s),
//! centroid height (f32 m).
//!
//! Limits and interpretation: the standard's text was not at hand. The Record Length field is
//! written as the length in bits of the record-specific fields (608 for a plume, 896 for a
//! puff, padding excluded). When reading, known record types ignore the Length field and skip
//! to the next multiple of 8 octets, so peers that count the 8-octet record header too still
//! decode; unknown record types are kept as raw octets using the Length field to find their
//! end. Only the plume and puff geometries are modelled; the other geometry and state records
//! (points, lines, spheres, COMBIC and flare states …) travel as
//! [`EnvironmentGeometry::Unknown`].

use dis_rs::enumerations::{Country, EntityKind, PlatformDomain};
use dis_rs::model::{EntityId, EntityType};

/// SISO-REF-010 UID 250: Gaussian Plume Record.
pub const RECORD_TYPE_GAUSSIAN_PLUME: u32 = 1_610_612_736;
/// SISO-REF-010 UID 250: Gaussian Puff Record.
pub const RECORD_TYPE_GAUSSIAN_PUFF: u32 = 1_879_048_192;
/// Octets of the Gaussian Plume record-specific fields.
pub const GAUSSIAN_PLUME_OCTETS: usize = 76;
/// Octets of the Gaussian Puff record-specific fields.
pub const GAUSSIAN_PUFF_OCTETS: usize = 112;
/// Octets before the first record.
pub const BODY_FIXED_OCTETS: usize = 20;
/// Records cig accepts in one PDU (a 1,500-octet datagram holds at most 11 puffs).
pub const MAX_RECORDS: usize = 1024;

/// Why an Environmental Process body could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EnvironmentalError {
    /// The body ended inside a field.
    #[error("Environmental Process: body ends at octet {at}, a field needs {needed} more")]
    Truncated {
        /// Offset where the missing field starts.
        at: usize,
        /// Octets that field needs.
        needed: usize,
    },
    /// More records declared than accepted.
    #[error("Environmental Process: {0} records declared, at most {MAX_RECORDS} accepted")]
    TooManyRecords(u16),
}

/// A Gaussian plume (SISO-REF-010 record UID 264).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussianPlume {
    /// Source location, ECEF metres.
    pub source_location_ecef_m: [f64; 3],
    /// Orientation psi, theta, phi (DIS Euler angles), radians.
    pub orientation_rad: [f32; 3],
    /// Plume length, metres.
    pub length_m: f32,
    /// Plume width, metres.
    pub width_m: f32,
    /// Plume height, metres.
    pub height_m: f32,
    /// d(length)/dt, m/s.
    pub length_rate_mps: f32,
    /// d(width)/dt, m/s.
    pub width_rate_mps: f32,
    /// d(height)/dt, m/s.
    pub height_rate_mps: f32,
    /// Leading edge centroid height, metres.
    pub leading_edge_centroid_height_m: f32,
    /// Leading edge velocity, m/s (ECEF).
    pub leading_edge_velocity_mps: [f32; 3],
}

/// A Gaussian puff (SISO-REF-010 record UID 265).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussianPuff {
    /// Puff location, ECEF metres.
    pub puff_location_ecef_m: [f64; 3],
    /// Origination location, ECEF metres.
    pub origination_location_ecef_m: [f64; 3],
    /// Sigma x, y, z, metres.
    pub sigma_m: [f32; 3],
    /// d(sigma)/dt for x, y, z, m/s.
    pub sigma_rate_mps: [f32; 3],
    /// Orientation psi, theta, phi, radians.
    pub orientation_rad: [f32; 3],
    /// Velocity, m/s (ECEF).
    pub velocity_mps: [f32; 3],
    /// Angular velocity about x, y, z, rad/s.
    pub angular_velocity_radps: [f32; 3],
    /// Centroid height, metres.
    pub centroid_height_m: f32,
}

/// The geometry or state carried by one environment record.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentGeometry {
    /// Gaussian plume.
    GaussianPlume(GaussianPlume),
    /// Gaussian puff.
    GaussianPuff(GaussianPuff),
    /// Any other record type, kept raw.
    Unknown {
        /// Record type (SISO-REF-010 UID 250).
        record_type: u32,
        /// Record-specific octets (padding excluded).
        data: Vec<u8>,
    },
}

/// One environment record.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentRecord {
    /// Record index (sequential numbering of records).
    pub index: u8,
    /// Its contents.
    pub geometry: EnvironmentGeometry,
}

/// An Environmental Process PDU body.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentalProcess {
    /// Environmental Process ID (site, application, object number).
    pub process_id: EntityId,
    /// Environment type (entity kind 4 "environmental").
    pub environment_type: EntityType,
    /// Model type (SISO-REF-010 UID 248; 0 = no statement).
    pub model_type: u8,
    /// Status bit 0: this is the last update of the process.
    pub is_last: bool,
    /// Status bit 1: the process is active.
    pub is_active: bool,
    /// Sequence number.
    pub sequence_number: u16,
    /// Environment records.
    pub records: Vec<EnvironmentRecord>,
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], EnvironmentalError> {
        let end = self
            .at
            .checked_add(n)
            .ok_or(EnvironmentalError::Truncated {
                at: self.at,
                needed: n,
            })?;
        let slice = self
            .bytes
            .get(self.at..end)
            .ok_or(EnvironmentalError::Truncated {
                at: self.at,
                needed: n,
            })?;
        self.at = end;
        Ok(slice)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N], EnvironmentalError> {
        let mut out = [0u8; N];
        out.copy_from_slice(self.take(N)?);
        Ok(out)
    }
    fn u8(&mut self) -> Result<u8, EnvironmentalError> {
        Ok(self.array::<1>()?[0])
    }
    fn u16(&mut self) -> Result<u16, EnvironmentalError> {
        Ok(u16::from_be_bytes(self.array()?))
    }
    fn u32(&mut self) -> Result<u32, EnvironmentalError> {
        Ok(u32::from_be_bytes(self.array()?))
    }
    fn f32(&mut self) -> Result<f32, EnvironmentalError> {
        Ok(f32::from_be_bytes(self.array()?))
    }
    fn f64(&mut self) -> Result<f64, EnvironmentalError> {
        Ok(f64::from_be_bytes(self.array()?))
    }
    fn f32x3(&mut self) -> Result<[f32; 3], EnvironmentalError> {
        Ok([self.f32()?, self.f32()?, self.f32()?])
    }
    fn f64x3(&mut self) -> Result<[f64; 3], EnvironmentalError> {
        Ok([self.f64()?, self.f64()?, self.f64()?])
    }
}

fn padded_to_8(n: usize) -> usize {
    n.div_ceil(8) * 8
}

fn decode_entity_type(r: &mut Reader<'_>) -> Result<EntityType, EnvironmentalError> {
    Ok(EntityType {
        kind: EntityKind::from(r.u8()?),
        domain: PlatformDomain::from(r.u8()?),
        country: Country::from(r.u16()?),
        category: r.u8()?,
        subcategory: r.u8()?,
        specific: r.u8()?,
        extra: r.u8()?,
    })
}

fn decode_plume(r: &mut Reader<'_>) -> Result<GaussianPlume, EnvironmentalError> {
    Ok(GaussianPlume {
        source_location_ecef_m: r.f64x3()?,
        orientation_rad: r.f32x3()?,
        length_m: r.f32()?,
        width_m: r.f32()?,
        height_m: r.f32()?,
        length_rate_mps: r.f32()?,
        width_rate_mps: r.f32()?,
        height_rate_mps: r.f32()?,
        leading_edge_centroid_height_m: r.f32()?,
        leading_edge_velocity_mps: r.f32x3()?,
    })
}

fn decode_puff(r: &mut Reader<'_>) -> Result<GaussianPuff, EnvironmentalError> {
    Ok(GaussianPuff {
        puff_location_ecef_m: r.f64x3()?,
        origination_location_ecef_m: r.f64x3()?,
        sigma_m: r.f32x3()?,
        sigma_rate_mps: r.f32x3()?,
        orientation_rad: r.f32x3()?,
        velocity_mps: r.f32x3()?,
        angular_velocity_radps: r.f32x3()?,
        centroid_height_m: r.f32()?,
    })
}

/// Decodes an Environmental Process body (the octets after the 12-octet PDU header).
///
/// # Errors
/// [`EnvironmentalError`] on a truncated body or an absurd record count; never panics.
pub fn decode_body(body: &[u8]) -> Result<EnvironmentalProcess, EnvironmentalError> {
    let mut r = Reader { bytes: body, at: 0 };
    let site = r.u16()?;
    let application = r.u16()?;
    let number = r.u16()?;
    let environment_type = decode_entity_type(&mut r)?;
    let model_type = r.u8()?;
    let status = r.u8()?;
    let count = r.u16()?;
    if usize::from(count) > MAX_RECORDS {
        return Err(EnvironmentalError::TooManyRecords(count));
    }
    let sequence_number = r.u16()?;
    let mut records = Vec::with_capacity(usize::from(count).min(64));
    for _ in 0..count {
        let start = r.at;
        let record_type = r.u32()?;
        let length_bits = r.u16()?;
        let index = r.u8()?;
        let _padding = r.u8()?;
        let geometry = match record_type {
            RECORD_TYPE_GAUSSIAN_PLUME => EnvironmentGeometry::GaussianPlume(decode_plume(&mut r)?),
            RECORD_TYPE_GAUSSIAN_PUFF => EnvironmentGeometry::GaussianPuff(decode_puff(&mut r)?),
            _ => {
                let octets = usize::from(length_bits).div_ceil(8);
                EnvironmentGeometry::Unknown {
                    record_type,
                    data: r.take(octets)?.to_vec(),
                }
            }
        };
        // Skip the padding to the 64-bit boundary (tolerate a body that ends right after the
        // last record's fields).
        let used = r.at - start;
        let pad = padded_to_8(used) - used;
        if r.at + pad <= body.len() {
            r.at += pad;
        } else {
            r.at = body.len();
        }
        records.push(EnvironmentRecord { index, geometry });
    }
    Ok(EnvironmentalProcess {
        process_id: EntityId::new(site, application, number),
        environment_type,
        model_type,
        is_last: status & 1 != 0,
        is_active: status & 2 != 0,
        sequence_number,
        records,
    })
}

fn put_f32x3(out: &mut Vec<u8>, v: [f32; 3]) {
    for c in v {
        out.extend_from_slice(&c.to_be_bytes());
    }
}

fn put_f64x3(out: &mut Vec<u8>, v: [f64; 3]) {
    for c in v {
        out.extend_from_slice(&c.to_be_bytes());
    }
}

fn record_fields(geometry: &EnvironmentGeometry) -> (u32, Vec<u8>) {
    let mut out = Vec::new();
    match geometry {
        EnvironmentGeometry::GaussianPlume(p) => {
            put_f64x3(&mut out, p.source_location_ecef_m);
            put_f32x3(&mut out, p.orientation_rad);
            for v in [
                p.length_m,
                p.width_m,
                p.height_m,
                p.length_rate_mps,
                p.width_rate_mps,
                p.height_rate_mps,
                p.leading_edge_centroid_height_m,
            ] {
                out.extend_from_slice(&v.to_be_bytes());
            }
            put_f32x3(&mut out, p.leading_edge_velocity_mps);
            (RECORD_TYPE_GAUSSIAN_PLUME, out)
        }
        EnvironmentGeometry::GaussianPuff(p) => {
            put_f64x3(&mut out, p.puff_location_ecef_m);
            put_f64x3(&mut out, p.origination_location_ecef_m);
            put_f32x3(&mut out, p.sigma_m);
            put_f32x3(&mut out, p.sigma_rate_mps);
            put_f32x3(&mut out, p.orientation_rad);
            put_f32x3(&mut out, p.velocity_mps);
            put_f32x3(&mut out, p.angular_velocity_radps);
            out.extend_from_slice(&p.centroid_height_m.to_be_bytes());
            (RECORD_TYPE_GAUSSIAN_PUFF, out)
        }
        EnvironmentGeometry::Unknown { record_type, data } => (*record_type, data.clone()),
    }
}

/// Encodes an Environmental Process body (without the PDU header). Records beyond
/// [`MAX_RECORDS`] and unknown-record data longer than 8191 octets are cut.
#[must_use]
pub fn encode_body(process: &EnvironmentalProcess) -> Vec<u8> {
    let mut out = Vec::with_capacity(BODY_FIXED_OCTETS + 120 * process.records.len());
    let id = &process.process_id;
    out.extend_from_slice(&id.simulation_address.site_id.to_be_bytes());
    out.extend_from_slice(&id.simulation_address.application_id.to_be_bytes());
    out.extend_from_slice(&id.entity_id.to_be_bytes());
    let t = &process.environment_type;
    out.push(u8::from(t.kind));
    out.push(u8::from(t.domain));
    out.extend_from_slice(&u16::from(t.country).to_be_bytes());
    out.extend_from_slice(&[t.category, t.subcategory, t.specific, t.extra]);
    out.push(process.model_type);
    out.push(u8::from(process.is_last) | (u8::from(process.is_active) << 1));
    let records = process
        .records
        .get(..MAX_RECORDS)
        .unwrap_or(&process.records);
    let count = u16::try_from(records.len()).unwrap_or(u16::MAX);
    out.extend_from_slice(&count.to_be_bytes());
    out.extend_from_slice(&process.sequence_number.to_be_bytes());
    for record in records {
        let (record_type, mut fields) = record_fields(&record.geometry);
        fields.truncate(8191);
        let length_bits = u16::try_from(fields.len() * 8).unwrap_or(u16::MAX);
        out.extend_from_slice(&record_type.to_be_bytes());
        out.extend_from_slice(&length_bits.to_be_bytes());
        out.push(record.index);
        out.push(0);
        out.extend_from_slice(&fields);
        let used = 8 + fields.len();
        out.resize(out.len() + padded_to_8(used) - used, 0);
    }
    out
}
