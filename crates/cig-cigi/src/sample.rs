//! Deterministic sample values for every packet type, for round-trip tests,
//! fuzz seeds and benchmarks.
//!
//! Algorithm: SplitMix64 (Steele, Lea and Flood, "Fast splittable
//! pseudorandom number generators", OOPSLA 2014) drives one draw per field.
//! Bit fields are masked to their declared width, floats are drawn finite
//! (so `PartialEq` round trips are meaningful) and strings are printable
//! ASCII short enough for the Image Generator Message limit.
//!
//! Limits: values are uniform over the bit patterns, not physically
//! plausible (a latitude may be 1e300); that is the point for a codec test.

/// A seeded source of pseudo-random words (SplitMix64).
#[derive(Debug, Clone)]
pub struct SampleSource {
    state: u64,
}

impl SampleSource {
    /// A source whose sequence is fixed by `seed` on every machine.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// Types that can be drawn from a [`SampleSource`].
pub trait Sample: Sized {
    /// One pseudo-random value.
    fn sample(source: &mut SampleSource) -> Self;
}

/// One field value; `bits` is the field width for packed integer fields
/// (0 means the whole type).
pub trait SampleField: Sized {
    /// One pseudo-random value of at most `bits` significant bits.
    fn sample_field(source: &mut SampleSource, bits: u32) -> Self;
}

fn low_bits(word: u64, bits: u32, full: u32) -> u64 {
    if bits == 0 || bits >= full {
        word
    } else {
        word & ((1u64 << bits) - 1)
    }
}

macro_rules! sample_int {
    ($($t:ty => $full:expr),*) => {$(
        impl SampleField for $t {
            #[allow(clippy::cast_possible_truncation, reason = "truncation to the field width is the intent")]
            fn sample_field(source: &mut SampleSource, bits: u32) -> Self {
                low_bits(source.next_u64(), bits, $full) as $t
            }
        }
    )*};
}
sample_int!(u8 => 8, u16 => 16, u32 => 32, u64 => 64, i8 => 8);

impl SampleField for bool {
    fn sample_field(source: &mut SampleSource, _bits: u32) -> Self {
        source.next_u64() & 1 == 1
    }
}

impl SampleField for f32 {
    fn sample_field(source: &mut SampleSource, _bits: u32) -> Self {
        let word = source.next_u64();
        #[allow(clippy::cast_possible_truncation, reason = "keeping the low 32 bits")]
        let value = f32::from_bits(word as u32);
        if value.is_finite() {
            value
        } else {
            0.5
        }
    }
}

impl SampleField for f64 {
    fn sample_field(source: &mut SampleSource, _bits: u32) -> Self {
        let value = f64::from_bits(source.next_u64());
        if value.is_finite() {
            value
        } else {
            0.25
        }
    }
}

impl<const N: usize> SampleField for [u32; N] {
    fn sample_field(source: &mut SampleSource, _bits: u32) -> Self {
        let mut out = [0u32; N];
        for word in &mut out {
            *word = u32::sample_field(source, 0);
        }
        out
    }
}

impl SampleField for String {
    fn sample_field(source: &mut SampleSource, _bits: u32) -> Self {
        let len = source.next_u64() % 100;
        (0..len)
            .map(|_| {
                let code = 0x20 + source.next_u64() % 0x5f;
                char::from(u8::try_from(code).unwrap_or(b'?'))
            })
            .collect()
    }
}

impl SampleField for Vec<u8> {
    fn sample_field(source: &mut SampleSource, _bits: u32) -> Self {
        let words = source.next_u64() % 8;
        #[allow(clippy::cast_possible_truncation, reason = "one byte per draw")]
        (0..words * 8).map(|_| source.next_u64() as u8).collect()
    }
}
