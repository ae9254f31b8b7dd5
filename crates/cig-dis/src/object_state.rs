//! Point Object State (PDU type 43) and Linear Object State (PDU type 44) PDUs: the Synthetic
//! Environment family's messages for objects anchored to the terrain — here dynamic terrain
//! edits passed between IGs: craters and fighting positions as point objects; ruts, tank ditches
//! and berms as linear objects made of segments.
//!
//! Source: IEEE 1278.1-2012 §7.10.4 (Point Object State PDU), §7.10.5 (Linear Object State PDU),
//! §6.2.52 (Linear Segment Parameter record), §6.2.63 (Object Identifier), §6.2.64 (Object Type),
//! §6.2.79 (Simulation Address) — clause numbers as Open-DIS's 2012 schema and open-dis-rust cite
//! them; enumerations from SISO-REF-010 (UID 225 object kind, 226 point and 227 linear object
//! types, 229 general object appearance, 240/241 modifications). `dis-rs`
//! 0.13 does not implement these PDUs, so they are written here, with the header handling of
//! [`crate::codec`] (the same 12-octet header as [`crate::environmental`]'s PDU).
//!
//! Algorithm: a straight big-endian field walk. Point Object State, 88 octets (offsets include
//! the header): header 0-11; object ID 12 (site, application, object: 3 × u16); referenced object
//! ID 18; update number 24 (u16); force ID 26 (u8); modifications 27 (u8); object type 28 (domain,
//! kind, category, subcategory: 4 × u8); location 32 (3 × f64, ECEF m); orientation 56 (psi,
//! theta, phi: 3 × f32 rad); specific appearance 68 (u32); general appearance 72 (u16); padding
//! 74 (2); requester 76 (site, application: 2 × u16); receiver 80; padding 84 (4).
//! Linear Object State, 40 + 64 n octets: header 0-11; object ID 12; referenced object ID 18;
//! update number 24 (u16); force ID 26 (u8); number of segments 27 (u8); requester 28; receiver
//! 32; object type 36; segments from 40, each 64 octets: segment number +0 (u8), modifications +1
//! (u8), general appearance +2 (u16), specific appearance +4 (u32), location +8 (3 × f64),
//! orientation +32 (3 × f32), length +44, width +48, height +52, depth +56 (4 × f32 m), padding
//! +60 (4).
//!
//! Field-width decision (the standard's text was not at hand; open implementations disagree on
//! the Linear Segment Parameter record): the segment's length, width, height and depth are
//! 32-bit floats and the record is 64 octets, as in AFSIM's `DisLinearSegmentParameterRecord`
//! (written to 1278.1-2012: `DisFloat32` sizes, a 32-bit pad, `cBASE_LENGTH_IN_OCTETS = 64`, its
//! field text "specified by a 32-bit floating point"), opendis7-java and the Python `opendis`
//! package (both generated from the 1278.1-2012 schema: four `float`s and a 32-bit pad) and
//! open-dis-rust. The 16-bit unsigned sizes (a 56-octet record) are the IEEE 1278.1a-1998 layout
//! (§5.2.48; KDIS `LINEAR_SEGMENT_PARAMETER_SIZE = 56`, Open-DIS's DIS 6 classes); the text "16-bit
//! unsigned integer" that survives in Open-DIS's DIS 7 schema comments is that older wording, and
//! Open-DIS C++'s DIS 7 class (u16 sizes, u16 specific appearance, no pad: 50 octets) contradicts
//! the standard's 32-bit specific appearance and 64-bit alignment. In the Point Object State PDU
//! every source that splits the 64-bit appearance (AFSIM, opendis7-java) orders it specific
//! appearance (u32), general appearance (u16), padding (u16); Open-DIS C++ and Python write the
//! same 8 octets as one opaque `double`. The update number is 16 bits (AFSIM, Open-DIS C++ and
//! Python; the 88-octet total); opendis7-java's `writeInt` of it is a 32-bit slip.
//!
//! Object types: SISO-REF-010 numbers them domain.kind.category with the subcategory below, so
//! "crater 1.1.3" is land 1, obstacle 1, crater 3 and its subcategory is the size (1 small,
//! 2 medium, 3 large), as opendis7-java's generated `objectTypes` classes (SISO-REF-010 v29) set
//! them. Point (UID 226) and linear (UID 227) types are separate tables: the same numbers name
//! different objects. SISO-REF-010 has no berm; see [`ObjectType`]'s constants.
//!
//! Limits: only protocol version 7 is read or written (the 1998 layout differs). A peer that uses
//! the 56-octet segment record is rejected, never misread: the declared PDU length must equal
//! 40 + 64 × the segment count, and the Point Object State PDU must be exactly 88 octets.
//! At most [`MAX_LINEAR_SEGMENTS`] (127) segments: 40 + 64 × 127 = 8168 octets is the largest
//! Linear Object State PDU within the standard's 8192-octet maximum PDU size (as open-dis-rust's
//! `MAX_PDU_SIZE_OCTETS`), although the count field could say 255. Locations, orientations and
//! sizes must be finite and sizes not negative (both ways: encoding refuses what decoding would
//! reject). Appearance, modification and force fields travel raw (SISO-REF-010 UID 229, 240, 241,
//! 6). Octets after the declared length (the next PDU of a bundled datagram) are ignored, as
//! [`crate::codec::decode_pdu`] does.

use crate::codec::{
    decode_header, DecodeError, DisVersion, EncodeHeader, PDU_HEADER_OCTETS,
    PROTOCOL_FAMILY_SYNTHETIC_ENVIRONMENT,
};

impl std::fmt::Display for ObjectId {
    /// `SITE:APPLICATION:OBJECT`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}:{}", self.site, self.application, self.object)
    }
}

impl std::fmt::Display for ObjectType {
    /// `DOMAIN.KIND.CATEGORY.SUBCATEGORY`, as SISO-REF-010 writes object types.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}.{}.{}.{}",
            self.domain, self.kind, self.category, self.subcategory
        )
    }
}

/// PDU type number of the Point Object State PDU (SISO-REF-010 UID 4).
pub const PDU_TYPE_POINT_OBJECT_STATE: u8 = 43;
/// PDU type number of the Linear Object State PDU (SISO-REF-010 UID 4).
pub const PDU_TYPE_LINEAR_OBJECT_STATE: u8 = 44;
/// Octets of a Point Object State PDU, header included.
pub const POINT_OBJECT_STATE_OCTETS: usize = 88;
/// Octets of a Linear Object State PDU before its first segment, header included.
pub const LINEAR_OBJECT_STATE_FIXED_OCTETS: usize = 40;
/// Octets of one Linear Segment Parameter record (IEEE 1278.1-2012 §6.2.52).
pub const LINEAR_SEGMENT_OCTETS: usize = 64;
/// The standard's maximum PDU size in octets.
pub const MAX_PDU_OCTETS: usize = 8192;
/// Segments accepted in one Linear Object State PDU: the most that fit [`MAX_PDU_OCTETS`].
pub const MAX_LINEAR_SEGMENTS: usize =
    (MAX_PDU_OCTETS - LINEAR_OBJECT_STATE_FIXED_OCTETS) / LINEAR_SEGMENT_OCTETS;

/// Why an Object State PDU could not be decoded or encoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ObjectStateError {
    /// The PDU header is unreadable or its length does not fit the buffer.
    #[error("Object State PDU header: {0}")]
    Header(#[from] DecodeError),
    /// A protocol version other than 7.
    #[error("Object State PDU: protocol version {0} is not read (only 7, IEEE 1278.1-2012)")]
    UnsupportedVersion(u8),
    /// The header names another PDU type.
    #[error("Object State PDU: PDU type {found}, expected {expected}")]
    WrongPduType {
        /// The type this decoder reads.
        expected: u8,
        /// The type in the header.
        found: u8,
    },
    /// The header names another protocol family.
    #[error("Object State PDU type {pdu_type}: protocol family {found}, expected 9 (Synthetic Environment)")]
    WrongFamily {
        /// PDU type number.
        pdu_type: u8,
        /// The family in the header.
        found: u8,
    },
    /// The declared PDU length differs from what the PDU's own fields need.
    #[error("Object State PDU type {pdu_type}: {declared_octets} octets declared, its fields need {expected_octets}")]
    LengthMismatch {
        /// PDU type number.
        pdu_type: u8,
        /// Declared length, header included.
        declared_octets: usize,
        /// Length the fields need, header included.
        expected_octets: usize,
    },
    /// The body ended inside its fixed fields.
    #[error(
        "Object State PDU type {pdu_type}: body ends at octet {at}, a field needs {needed} more"
    )]
    Truncated {
        /// PDU type number.
        pdu_type: u8,
        /// Body offset where the missing field starts.
        at: usize,
        /// Octets that field needs.
        needed: usize,
    },
    /// More segments than [`MAX_LINEAR_SEGMENTS`].
    #[error("Linear Object State PDU: {0} segments, at most {MAX_LINEAR_SEGMENTS} fit the 8192-octet PDU limit")]
    TooManySegments(usize),
    /// A location, orientation or size is NaN or infinite.
    #[error("Object State PDU: {field} is not finite")]
    NotFinite {
        /// The field, e.g. `segments[2].width_m`.
        field: String,
    },
    /// A segment size is negative.
    #[error("Object State PDU: {field} is negative")]
    NegativeSize {
        /// The field, e.g. `segments[0].depth_m`.
        field: String,
    },
}

/// Simulation Address record (IEEE 1278.1-2012 §6.2.79).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SimulationAddress {
    /// Site number.
    pub site: u16,
    /// Application number.
    pub application: u16,
}

/// Object Identifier record: simulation address and object number (§6.2.63).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ObjectId {
    /// Site number.
    pub site: u16,
    /// Application number.
    pub application: u16,
    /// Object number.
    pub object: u16,
}

/// Object Type record (§6.2.64): domain (SISO-REF-010 UID 8), object kind (UID 225), category
/// and subcategory (UID 226 for point objects, 227 for linear objects).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ObjectType {
    /// Domain (1 = land).
    pub domain: u8,
    /// Object kind (1 obstacle, 2 prepared position, 3 cultural feature, ...).
    pub kind: u8,
    /// Category within the kind.
    pub category: u8,
    /// Subcategory within the category (0 = other / unspecified).
    pub subcategory: u8,
}

impl ObjectType {
    const fn land(kind: u8, category: u8, subcategory: u8) -> ObjectType {
        ObjectType {
            domain: 1,
            kind,
            category,
            subcategory,
        }
    }

    /// Point object (UID 226) land 1, obstacle 1, crater 3, subcategory 0 (other).
    pub const POINT_CRATER: ObjectType = ObjectType::land(1, 3, 0);
    /// Point object 1.1.3, subcategory 1: small crater.
    pub const POINT_CRATER_SMALL: ObjectType = ObjectType::land(1, 3, 1);
    /// Point object 1.1.3, subcategory 2: medium crater.
    pub const POINT_CRATER_MEDIUM: ObjectType = ObjectType::land(1, 3, 2);
    /// Point object 1.1.3, subcategory 3: large crater.
    pub const POINT_CRATER_LARGE: ObjectType = ObjectType::land(1, 3, 3);
    /// Point object land 1, prepared position 2, vehicle defilade 1, subcategory 4: tank.
    pub const POINT_VEHICLE_DEFILADE_TANK: ObjectType = ObjectType::land(2, 1, 4);
    /// Point object land 1, prepared position 2, infantry fighting position 2.
    pub const POINT_INFANTRY_FIGHTING_POSITION: ObjectType = ObjectType::land(2, 2, 0);
    /// Point object land 1, cultural feature 3, disturbed earth 3.
    pub const POINT_DISTURBED_EARTH: ObjectType = ObjectType::land(3, 3, 0);
    /// Linear object (UID 227) land 1, obstacle 1, tank ditch 1.
    pub const LINEAR_TANK_DITCH: ObjectType = ObjectType::land(1, 1, 0);
    /// Linear object land 1, obstacle 1, rut 5.
    pub const LINEAR_RUT: ObjectType = ObjectType::land(1, 5, 0);
    /// Linear object land 1, cultural feature 3, tire tracks 2.
    pub const LINEAR_TIRE_TRACKS: ObjectType = ObjectType::land(3, 2, 0);
}

/// A Point Object State PDU (IEEE 1278.1-2012 §7.10.4).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointObjectState {
    /// The object.
    pub object_id: ObjectId,
    /// The object this one is associated with (all zero: none).
    pub referenced_object_id: ObjectId,
    /// Update number, starting at 1, one per state change.
    pub update_number: u16,
    /// Force that created or modified the object (SISO-REF-010 UID 6).
    pub force_id: u8,
    /// Modifications (UID 240: bit 0 location, bit 1 orientation changed).
    pub modifications: u8,
    /// Object type.
    pub object_type: ObjectType,
    /// Location, ECEF metres.
    pub location_ecef_m: [f64; 3],
    /// Orientation psi, theta, phi (DIS Euler angles), radians.
    pub orientation_rad: [f32; 3],
    /// Specific appearance (32 bits, by object type).
    pub specific_appearance: u32,
    /// General appearance (UID 229: percent complete, damage, ...).
    pub general_appearance: u16,
    /// Simulation that sent the PDU to the environment manager.
    pub requester: SimulationAddress,
    /// Simulation that is to receive it.
    pub receiver: SimulationAddress,
}

/// One Linear Segment Parameter record (IEEE 1278.1-2012 §6.2.52).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LinearSegment {
    /// Segment number.
    pub segment_number: u8,
    /// Modifications (UID 241: bit 0 location, bit 1 orientation changed).
    pub modifications: u8,
    /// General appearance (UID 229).
    pub general_appearance: u16,
    /// Specific appearance (32 bits, by object type).
    pub specific_appearance: u32,
    /// Segment location, ECEF metres.
    pub location_ecef_m: [f64; 3],
    /// Segment orientation psi, theta, phi, radians.
    pub orientation_rad: [f32; 3],
    /// Length along +x, metres.
    pub length_m: f32,
    /// Total width, half each side of x, metres.
    pub width_m: f32,
    /// Height above ground, metres.
    pub height_m: f32,
    /// Depth below ground, metres.
    pub depth_m: f32,
}

/// A Linear Object State PDU (IEEE 1278.1-2012 §7.10.5).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinearObjectState {
    /// The object.
    pub object_id: ObjectId,
    /// The object this one is associated with (all zero: none).
    pub referenced_object_id: ObjectId,
    /// Update number, starting at 1, one per state change.
    pub update_number: u16,
    /// Force that created or modified the object (SISO-REF-010 UID 6).
    pub force_id: u8,
    /// Simulation that sent the PDU to the environment manager.
    pub requester: SimulationAddress,
    /// Simulation that is to receive it.
    pub receiver: SimulationAddress,
    /// Object type.
    pub object_type: ObjectType,
    /// Segments, at most [`MAX_LINEAR_SEGMENTS`].
    pub segments: Vec<LinearSegment>,
}

const XYZ: [&str; 3] = ["[0]", "[1]", "[2]"];

fn check_finite64(prefix: &str, name: &str, v: [f64; 3]) -> Result<(), ObjectStateError> {
    for (c, suffix) in v.iter().zip(XYZ) {
        if !c.is_finite() {
            return Err(ObjectStateError::NotFinite {
                field: format!("{prefix}{name}{suffix}"),
            });
        }
    }
    Ok(())
}

fn check_finite32(prefix: &str, name: &str, v: [f32; 3]) -> Result<(), ObjectStateError> {
    for (c, suffix) in v.iter().zip(XYZ) {
        if !c.is_finite() {
            return Err(ObjectStateError::NotFinite {
                field: format!("{prefix}{name}{suffix}"),
            });
        }
    }
    Ok(())
}

impl PointObjectState {
    /// Checks what the wire format carries but cig refuses: non-finite location or orientation.
    ///
    /// # Errors
    /// [`ObjectStateError::NotFinite`] naming the first bad field.
    pub fn validate(&self) -> Result<(), ObjectStateError> {
        check_finite64("", "location_ecef_m", self.location_ecef_m)?;
        check_finite32("", "orientation_rad", self.orientation_rad)
    }
}

impl LinearSegment {
    fn validate(&self, index: usize) -> Result<(), ObjectStateError> {
        let prefix = format!("segments[{index}].");
        check_finite64(&prefix, "location_ecef_m", self.location_ecef_m)?;
        check_finite32(&prefix, "orientation_rad", self.orientation_rad)?;
        for (name, v) in [
            ("length_m", self.length_m),
            ("width_m", self.width_m),
            ("height_m", self.height_m),
            ("depth_m", self.depth_m),
        ] {
            if !v.is_finite() {
                return Err(ObjectStateError::NotFinite {
                    field: format!("{prefix}{name}"),
                });
            }
            if v < 0.0 {
                return Err(ObjectStateError::NegativeSize {
                    field: format!("{prefix}{name}"),
                });
            }
        }
        Ok(())
    }
}

impl LinearObjectState {
    /// Checks the segment count and every segment's location, orientation and sizes.
    ///
    /// # Errors
    /// [`ObjectStateError::TooManySegments`], [`ObjectStateError::NotFinite`] or
    /// [`ObjectStateError::NegativeSize`] naming the first bad field.
    pub fn validate(&self) -> Result<(), ObjectStateError> {
        if self.segments.len() > MAX_LINEAR_SEGMENTS {
            return Err(ObjectStateError::TooManySegments(self.segments.len()));
        }
        self.segments
            .iter()
            .enumerate()
            .try_for_each(|(i, s)| s.validate(i))
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    pdu_type: u8,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], ObjectStateError> {
        let truncated = ObjectStateError::Truncated {
            pdu_type: self.pdu_type,
            at: self.at,
            needed: n,
        };
        let end = self.at.checked_add(n).ok_or(truncated.clone())?;
        let slice = self.bytes.get(self.at..end).ok_or(truncated)?;
        self.at = end;
        Ok(slice)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N], ObjectStateError> {
        let mut out = [0u8; N];
        out.copy_from_slice(self.take(N)?);
        Ok(out)
    }
    fn u8(&mut self) -> Result<u8, ObjectStateError> {
        Ok(self.array::<1>()?[0])
    }
    fn u16(&mut self) -> Result<u16, ObjectStateError> {
        Ok(u16::from_be_bytes(self.array()?))
    }
    fn u32(&mut self) -> Result<u32, ObjectStateError> {
        Ok(u32::from_be_bytes(self.array()?))
    }
    fn f32(&mut self) -> Result<f32, ObjectStateError> {
        Ok(f32::from_be_bytes(self.array()?))
    }
    fn f32x3(&mut self) -> Result<[f32; 3], ObjectStateError> {
        Ok([self.f32()?, self.f32()?, self.f32()?])
    }
    fn f64x3(&mut self) -> Result<[f64; 3], ObjectStateError> {
        let mut out = [0.0; 3];
        for c in &mut out {
            *c = f64::from_be_bytes(self.array()?);
        }
        Ok(out)
    }
    fn object_id(&mut self) -> Result<ObjectId, ObjectStateError> {
        Ok(ObjectId {
            site: self.u16()?,
            application: self.u16()?,
            object: self.u16()?,
        })
    }
    fn simulation_address(&mut self) -> Result<SimulationAddress, ObjectStateError> {
        Ok(SimulationAddress {
            site: self.u16()?,
            application: self.u16()?,
        })
    }
    fn object_type(&mut self) -> Result<ObjectType, ObjectStateError> {
        let [domain, kind, category, subcategory] = self.array()?;
        Ok(ObjectType {
            domain,
            kind,
            category,
            subcategory,
        })
    }
    fn segment(&mut self) -> Result<LinearSegment, ObjectStateError> {
        let segment = LinearSegment {
            segment_number: self.u8()?,
            modifications: self.u8()?,
            general_appearance: self.u16()?,
            specific_appearance: self.u32()?,
            location_ecef_m: self.f64x3()?,
            orientation_rad: self.f32x3()?,
            length_m: self.f32()?,
            width_m: self.f32()?,
            height_m: self.f32()?,
            depth_m: self.f32()?,
        };
        let _padding = self.take(4)?;
        Ok(segment)
    }
}

struct Writer(Vec<u8>);

impl Writer {
    fn bytes(&mut self, b: &[u8]) {
        self.0.extend_from_slice(b);
    }
    fn u16(&mut self, v: u16) {
        self.bytes(&v.to_be_bytes());
    }
    fn f32x3(&mut self, v: [f32; 3]) {
        for c in v {
            self.bytes(&c.to_be_bytes());
        }
    }
    fn f64x3(&mut self, v: [f64; 3]) {
        for c in v {
            self.bytes(&c.to_be_bytes());
        }
    }
    fn object_id(&mut self, id: ObjectId) {
        self.u16(id.site);
        self.u16(id.application);
        self.u16(id.object);
    }
    fn simulation_address(&mut self, a: SimulationAddress) {
        self.u16(a.site);
        self.u16(a.application);
    }
    fn object_type(&mut self, t: ObjectType) {
        self.bytes(&[t.domain, t.kind, t.category, t.subcategory]);
    }
}

/// Decodes a Point Object State body: the octets after the 12-octet header, cut to the header's
/// declared length (as [`crate::codec::decode_pdu`] hands bodies on).
///
/// # Errors
/// [`ObjectStateError::LengthMismatch`] unless the body is exactly 76 octets;
/// [`ObjectStateError::NotFinite`] for a NaN or infinite location or orientation. Never panics.
pub fn decode_point_object_state_body(body: &[u8]) -> Result<PointObjectState, ObjectStateError> {
    let expected = POINT_OBJECT_STATE_OCTETS - PDU_HEADER_OCTETS;
    if body.len() != expected {
        return Err(ObjectStateError::LengthMismatch {
            pdu_type: PDU_TYPE_POINT_OBJECT_STATE,
            declared_octets: PDU_HEADER_OCTETS.saturating_add(body.len()),
            expected_octets: POINT_OBJECT_STATE_OCTETS,
        });
    }
    let mut r = Reader {
        bytes: body,
        at: 0,
        pdu_type: PDU_TYPE_POINT_OBJECT_STATE,
    };
    let object_id = r.object_id()?;
    let referenced_object_id = r.object_id()?;
    let update_number = r.u16()?;
    let force_id = r.u8()?;
    let modifications = r.u8()?;
    let object_type = r.object_type()?;
    let location_ecef_m = r.f64x3()?;
    let orientation_rad = r.f32x3()?;
    let specific_appearance = r.u32()?;
    let general_appearance = r.u16()?;
    let _padding = r.take(2)?;
    let requester = r.simulation_address()?;
    let receiver = r.simulation_address()?;
    let _padding = r.take(4)?;
    let pdu = PointObjectState {
        object_id,
        referenced_object_id,
        update_number,
        force_id,
        modifications,
        object_type,
        location_ecef_m,
        orientation_rad,
        specific_appearance,
        general_appearance,
        requester,
        receiver,
    };
    pdu.validate()?;
    Ok(pdu)
}

/// Encodes a Point Object State body (76 octets, without the PDU header).
///
/// # Errors
/// [`ObjectStateError::NotFinite`] for a NaN or infinite location or orientation.
pub fn encode_point_object_state_body(pdu: &PointObjectState) -> Result<Vec<u8>, ObjectStateError> {
    pdu.validate()?;
    let mut w = Writer(Vec::with_capacity(
        POINT_OBJECT_STATE_OCTETS - PDU_HEADER_OCTETS,
    ));
    w.object_id(pdu.object_id);
    w.object_id(pdu.referenced_object_id);
    w.u16(pdu.update_number);
    w.bytes(&[pdu.force_id, pdu.modifications]);
    w.object_type(pdu.object_type);
    w.f64x3(pdu.location_ecef_m);
    w.f32x3(pdu.orientation_rad);
    w.bytes(&pdu.specific_appearance.to_be_bytes());
    w.u16(pdu.general_appearance);
    w.bytes(&[0; 2]);
    w.simulation_address(pdu.requester);
    w.simulation_address(pdu.receiver);
    w.bytes(&[0; 4]);
    Ok(w.0)
}

/// Decodes a Linear Object State body: the octets after the 12-octet header, cut to the
/// header's declared length.
///
/// # Errors
/// [`ObjectStateError::Truncated`] when the fixed fields are cut;
/// [`ObjectStateError::TooManySegments`] for more than [`MAX_LINEAR_SEGMENTS`];
/// [`ObjectStateError::LengthMismatch`] unless the body is exactly 28 + 64 × count octets;
/// [`ObjectStateError::NotFinite`] / [`ObjectStateError::NegativeSize`] for a bad segment.
/// Never panics, never allocates more than the body's own segments need.
pub fn decode_linear_object_state_body(body: &[u8]) -> Result<LinearObjectState, ObjectStateError> {
    let mut r = Reader {
        bytes: body,
        at: 0,
        pdu_type: PDU_TYPE_LINEAR_OBJECT_STATE,
    };
    let object_id = r.object_id()?;
    let referenced_object_id = r.object_id()?;
    let update_number = r.u16()?;
    let force_id = r.u8()?;
    let count = usize::from(r.u8()?);
    let requester = r.simulation_address()?;
    let receiver = r.simulation_address()?;
    let object_type = r.object_type()?;
    if count > MAX_LINEAR_SEGMENTS {
        return Err(ObjectStateError::TooManySegments(count));
    }
    let expected_body = r.at + count * LINEAR_SEGMENT_OCTETS;
    if body.len() != expected_body {
        return Err(ObjectStateError::LengthMismatch {
            pdu_type: PDU_TYPE_LINEAR_OBJECT_STATE,
            declared_octets: PDU_HEADER_OCTETS.saturating_add(body.len()),
            expected_octets: PDU_HEADER_OCTETS + expected_body,
        });
    }
    let mut segments = Vec::with_capacity(count);
    for _ in 0..count {
        segments.push(r.segment()?);
    }
    let pdu = LinearObjectState {
        object_id,
        referenced_object_id,
        update_number,
        force_id,
        requester,
        receiver,
        object_type,
        segments,
    };
    pdu.validate()?;
    Ok(pdu)
}

/// Encodes a Linear Object State body (28 + 64 × segments octets, without the PDU header).
///
/// # Errors
/// [`ObjectStateError::TooManySegments`], [`ObjectStateError::NotFinite`] or
/// [`ObjectStateError::NegativeSize`].
pub fn encode_linear_object_state_body(
    pdu: &LinearObjectState,
) -> Result<Vec<u8>, ObjectStateError> {
    pdu.validate()?;
    let count = u8::try_from(pdu.segments.len())
        .map_err(|_| ObjectStateError::TooManySegments(pdu.segments.len()))?;
    let mut w = Writer(Vec::with_capacity(
        LINEAR_OBJECT_STATE_FIXED_OCTETS - PDU_HEADER_OCTETS
            + LINEAR_SEGMENT_OCTETS * pdu.segments.len(),
    ));
    w.object_id(pdu.object_id);
    w.object_id(pdu.referenced_object_id);
    w.u16(pdu.update_number);
    w.bytes(&[pdu.force_id, count]);
    w.simulation_address(pdu.requester);
    w.simulation_address(pdu.receiver);
    w.object_type(pdu.object_type);
    for s in &pdu.segments {
        w.bytes(&[s.segment_number, s.modifications]);
        w.u16(s.general_appearance);
        w.bytes(&s.specific_appearance.to_be_bytes());
        w.f64x3(s.location_ecef_m);
        w.f32x3(s.orientation_rad);
        for v in [s.length_m, s.width_m, s.height_m, s.depth_m] {
            w.bytes(&v.to_be_bytes());
        }
        w.bytes(&[0; 4]);
    }
    Ok(w.0)
}

/// Reads and checks the header of a PDU of `pdu_type` and returns its body, cut to the declared
/// length.
fn checked_body(bytes: &[u8], pdu_type: u8) -> Result<&[u8], ObjectStateError> {
    let header = decode_header(bytes)?;
    if header.version != DisVersion::V7 {
        return Err(ObjectStateError::UnsupportedVersion(header.version.octet()));
    }
    if header.pdu_type != pdu_type {
        return Err(ObjectStateError::WrongPduType {
            expected: pdu_type,
            found: header.pdu_type,
        });
    }
    if header.protocol_family != PROTOCOL_FAMILY_SYNTHETIC_ENVIRONMENT {
        return Err(ObjectStateError::WrongFamily {
            pdu_type,
            found: header.protocol_family,
        });
    }
    // decode_header has checked PDU_HEADER_OCTETS <= declared <= bytes.len().
    Ok(bytes
        .get(PDU_HEADER_OCTETS..usize::from(header.length_octets))
        .unwrap_or_default())
}

/// Prefixes a body with a version 7 PDU header (PDU status and padding zero).
fn with_header(
    header: EncodeHeader,
    pdu_type: u8,
    body: &[u8],
) -> Result<Vec<u8>, ObjectStateError> {
    if header.version != DisVersion::V7 {
        return Err(ObjectStateError::UnsupportedVersion(header.version.octet()));
    }
    let total = PDU_HEADER_OCTETS + body.len();
    // Bodies are bounded by MAX_LINEAR_SEGMENTS, so this holds; kept as an error, not a panic.
    let length = u16::try_from(total).map_err(|_| ObjectStateError::LengthMismatch {
        pdu_type,
        declared_octets: total,
        expected_octets: MAX_PDU_OCTETS,
    })?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(&[
        header.version.octet(),
        header.exercise_id,
        pdu_type,
        PROTOCOL_FAMILY_SYNTHETIC_ENVIRONMENT,
    ]);
    out.extend_from_slice(&header.timestamp.to_be_bytes());
    out.extend_from_slice(&length.to_be_bytes());
    out.extend_from_slice(&[0, 0]);
    out.extend_from_slice(body);
    Ok(out)
}

/// Encodes a whole Point Object State PDU (88 octets).
///
/// # Errors
/// [`ObjectStateError::UnsupportedVersion`] for a version 6 header;
/// [`ObjectStateError::NotFinite`] for a NaN or infinite location or orientation.
pub fn encode_point_object_state(
    header: EncodeHeader,
    pdu: &PointObjectState,
) -> Result<Vec<u8>, ObjectStateError> {
    with_header(
        header,
        PDU_TYPE_POINT_OBJECT_STATE,
        &encode_point_object_state_body(pdu)?,
    )
}

/// Decodes the Point Object State PDU at the start of `bytes` (octets after its declared length
/// are ignored).
///
/// # Errors
/// Any [`ObjectStateError`]; never panics on any input.
pub fn decode_point_object_state(bytes: &[u8]) -> Result<PointObjectState, ObjectStateError> {
    decode_point_object_state_body(checked_body(bytes, PDU_TYPE_POINT_OBJECT_STATE)?)
}

/// Encodes a whole Linear Object State PDU (40 + 64 × segments octets).
///
/// # Errors
/// [`ObjectStateError::UnsupportedVersion`] for a version 6 header,
/// [`ObjectStateError::TooManySegments`], [`ObjectStateError::NotFinite`] or
/// [`ObjectStateError::NegativeSize`].
pub fn encode_linear_object_state(
    header: EncodeHeader,
    pdu: &LinearObjectState,
) -> Result<Vec<u8>, ObjectStateError> {
    with_header(
        header,
        PDU_TYPE_LINEAR_OBJECT_STATE,
        &encode_linear_object_state_body(pdu)?,
    )
}

/// Decodes the Linear Object State PDU at the start of `bytes` (octets after its declared length
/// are ignored).
///
/// # Errors
/// Any [`ObjectStateError`]; never panics on any input.
pub fn decode_linear_object_state(bytes: &[u8]) -> Result<LinearObjectState, ObjectStateError> {
    decode_linear_object_state_body(checked_body(bytes, PDU_TYPE_LINEAR_OBJECT_STATE)?)
}
