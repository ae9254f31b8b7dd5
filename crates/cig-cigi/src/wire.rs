//! Field access shared by the decoder and the encoder.
//!
//! Algorithm: every packet layout is written once, as a function that visits
//! each field with its byte offset (and bit position for packed flags). The
//! same function decodes (the visitor copies bytes into the field) and
//! encodes (the visitor copies the field into a zeroed packet buffer), so the
//! two directions cannot disagree. Multi-byte fields use the byte order of the
//! message (SISO-STD-013 3.3 section 4.1.1 "Byte Swapping": a receiver swaps
//! 16/32/64-bit fields as whole units; single bytes and bit fields inside one
//! byte are never swapped). Bit numbering follows the standard: bit 0 is the
//! least significant bit of the byte.
//!
//! Limits: reads past the end of the packet slice yield zero; callers check the
//! declared packet size against the layout size before visiting, so this is a
//! defence, never the normal path.

/// Byte order of the multi-byte fields of a message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ByteOrder {
    /// Most significant byte first (network order).
    BigEndian,
    /// Least significant byte first (x86, most ARM hosts).
    LittleEndian,
}

/// A visitor over the fields of one packet.
pub(crate) trait FieldIo {
    fn u8(&mut self, offset: usize, value: &mut u8);
    fn i8(&mut self, offset: usize, value: &mut i8) {
        let mut raw = value.to_ne_bytes()[0];
        self.u8(offset, &mut raw);
        *value = i8::from_ne_bytes([raw]);
    }
    fn u16(&mut self, offset: usize, value: &mut u16);
    fn u32(&mut self, offset: usize, value: &mut u32);
    fn f32(&mut self, offset: usize, value: &mut f32) {
        let mut bits = value.to_bits();
        self.u32(offset, &mut bits);
        *value = f32::from_bits(bits);
    }
    fn u64(&mut self, offset: usize, value: &mut u64);
    fn f64(&mut self, offset: usize, value: &mut f64) {
        let mut bits = value.to_bits();
        self.u64(offset, &mut bits);
        *value = f64::from_bits(bits);
    }
    /// A field of `width` bits starting at bit `shift` of byte `offset`.
    fn bits(&mut self, offset: usize, shift: u32, width: u32, value: &mut u8);
    /// A one-bit flag at bit `bit` of byte `offset`.
    fn flag(&mut self, offset: usize, bit: u32, value: &mut bool) {
        let mut raw = u8::from(*value);
        self.bits(offset, bit, 1, &mut raw);
        *value = raw != 0;
    }
}

fn mask(width: u32) -> u8 {
    if width >= 8 {
        0xff
    } else {
        (1u8 << width) - 1
    }
}

/// Reads fields out of one packet's bytes.
pub(crate) struct Reader<'a> {
    bytes: &'a [u8],
    order: ByteOrder,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(bytes: &'a [u8], order: ByteOrder) -> Self {
        Self { bytes, order }
    }

    fn array<const N: usize>(&self, offset: usize) -> [u8; N] {
        let mut out = [0u8; N];
        if let Some(src) = offset
            .checked_add(N)
            .and_then(|end| self.bytes.get(offset..end))
        {
            out.copy_from_slice(src);
        }
        out
    }
}

impl FieldIo for Reader<'_> {
    fn u8(&mut self, offset: usize, value: &mut u8) {
        *value = self.bytes.get(offset).copied().unwrap_or(0);
    }
    fn u16(&mut self, offset: usize, value: &mut u16) {
        let a = self.array::<2>(offset);
        *value = match self.order {
            ByteOrder::BigEndian => u16::from_be_bytes(a),
            ByteOrder::LittleEndian => u16::from_le_bytes(a),
        };
    }
    fn u32(&mut self, offset: usize, value: &mut u32) {
        let a = self.array::<4>(offset);
        *value = match self.order {
            ByteOrder::BigEndian => u32::from_be_bytes(a),
            ByteOrder::LittleEndian => u32::from_le_bytes(a),
        };
    }
    fn u64(&mut self, offset: usize, value: &mut u64) {
        let a = self.array::<8>(offset);
        *value = match self.order {
            ByteOrder::BigEndian => u64::from_be_bytes(a),
            ByteOrder::LittleEndian => u64::from_le_bytes(a),
        };
    }
    fn bits(&mut self, offset: usize, shift: u32, width: u32, value: &mut u8) {
        let byte = self.bytes.get(offset).copied().unwrap_or(0);
        *value = byte.checked_shr(shift).unwrap_or(0) & mask(width);
    }
}

/// Writes fields into one packet's bytes (the buffer starts zeroed, so
/// reserved fields are written as zero as the standard requires).
pub(crate) struct Writer<'a> {
    bytes: &'a mut [u8],
    order: ByteOrder,
}

impl<'a> Writer<'a> {
    pub(crate) fn new(bytes: &'a mut [u8], order: ByteOrder) -> Self {
        Self { bytes, order }
    }

    fn put(&mut self, offset: usize, src: &[u8]) {
        if let Some(dst) = offset
            .checked_add(src.len())
            .and_then(|end| self.bytes.get_mut(offset..end))
        {
            dst.copy_from_slice(src);
        }
    }
}

impl FieldIo for Writer<'_> {
    fn u8(&mut self, offset: usize, value: &mut u8) {
        self.put(offset, &[*value]);
    }
    fn u16(&mut self, offset: usize, value: &mut u16) {
        let a = match self.order {
            ByteOrder::BigEndian => value.to_be_bytes(),
            ByteOrder::LittleEndian => value.to_le_bytes(),
        };
        self.put(offset, &a);
    }
    fn u32(&mut self, offset: usize, value: &mut u32) {
        let a = match self.order {
            ByteOrder::BigEndian => value.to_be_bytes(),
            ByteOrder::LittleEndian => value.to_le_bytes(),
        };
        self.put(offset, &a);
    }
    fn u64(&mut self, offset: usize, value: &mut u64) {
        let a = match self.order {
            ByteOrder::BigEndian => value.to_be_bytes(),
            ByteOrder::LittleEndian => value.to_le_bytes(),
        };
        self.put(offset, &a);
    }
    fn bits(&mut self, offset: usize, shift: u32, width: u32, value: &mut u8) {
        if let Some(byte) = self.bytes.get_mut(offset) {
            let m = mask(width);
            let cleared = *byte & !m.checked_shl(shift).unwrap_or(0);
            *byte = cleared | (*value & m).checked_shl(shift).unwrap_or(0);
        }
    }
}
