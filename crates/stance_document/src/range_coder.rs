//! A binary adaptive range coder (the LZMA scheme: 11-bit probabilities, carry-propagating
//! encoder) and the integer models the link format is written with.
//!
//! Integers are coded as their bit length (an adaptive 7-level bit tree per context) followed by
//! the bits below the leading one: the first of them adaptive per bit length, the rest direct.
//! On quantised joint angles this stays within about 0.2 bit per value of the entropy, which a
//! byte-oriented compressor (deflate, LZ4) cannot approach on such data.

const PROB_BITS: u32 = 12;
const PROB_ONE: u16 = 1 << PROB_BITS;
const PROB_INIT: u16 = PROB_ONE / 2;
/// Probabilities stay within [PROB_MIN, PROB_ONE - PROB_MIN].
const PROB_MIN: i32 = 24;
/// The adaptation rate goes from 1/2 (first bit seen) to 1/RATE_LIMIT: a running average of
/// the bits seen (the Krichevsky-Trofimov estimate) that becomes a moving one.
const RATE_LIMIT: u16 = 24;
const TOP: u32 = 1 << 24;
/// Most zero bytes [`Encoder::finish`] leaves off the end of a stream: the decoder reads them
/// back as zeros past the end, and a stream that needs more is damaged (`Decoder::overrun`).
pub(crate) const MAX_DROPPED_ZEROS: usize = 16;

/// An adaptive probability that the next bit is 0, and how many bits it has seen.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bit {
    p: u16,
    seen: u16,
}

impl Bit {
    fn update(&mut self, bit: bool) {
        let divisor = i32::from((self.seen + 2).min(RATE_LIMIT));
        self.seen = (self.seen + 1).min(RATE_LIMIT);
        let p = i32::from(self.p);
        let target = if bit { 0 } else { i32::from(PROB_ONE) };
        let p = (p + (target - p) / divisor).clamp(PROB_MIN, i32::from(PROB_ONE) - PROB_MIN);
        self.p = p as u16;
    }
}

impl Default for Bit {
    fn default() -> Self {
        Bit {
            p: PROB_INIT,
            seen: 0,
        }
    }
}

/// Writes bits into bytes.
#[derive(Debug)]
pub(crate) struct Encoder {
    low: u64,
    range: u32,
    cache: u8,
    cache_size: u64,
    out: Vec<u8>,
}

impl Encoder {
    pub(crate) fn new() -> Self {
        Self {
            low: 0,
            range: u32::MAX,
            cache: 0,
            cache_size: 1,
            out: Vec::new(),
        }
    }

    fn shift_low(&mut self) {
        if self.low < 0xFF00_0000 || self.low > 0xFFFF_FFFF {
            let carry = (self.low >> 32) as u8;
            let mut temp = self.cache;
            loop {
                self.out.push(temp.wrapping_add(carry));
                temp = 0xFF;
                self.cache_size -= 1;
                if self.cache_size == 0 {
                    break;
                }
            }
            self.cache = ((self.low >> 24) & 0xFF) as u8;
        }
        self.cache_size += 1;
        self.low = (self.low & 0x00FF_FFFF) << 8;
    }

    fn normalize(&mut self) {
        while self.range < TOP {
            self.range <<= 8;
            self.shift_low();
        }
    }

    /// One bit with an adaptive probability.
    pub(crate) fn bit(&mut self, p: &mut Bit, bit: bool) {
        let bound = (self.range >> PROB_BITS) * u32::from(p.p);
        if bit {
            self.low += u64::from(bound);
            self.range -= bound;
        } else {
            self.range = bound;
        }
        p.update(bit);
        self.normalize();
    }

    /// The low `count` bits of `value`, most significant first, each at probability 1/2.
    pub(crate) fn direct(&mut self, value: u64, count: u32) {
        for i in (0..count).rev() {
            self.range >>= 1;
            if (value >> i) & 1 == 1 {
                self.low += u64::from(self.range);
            }
            self.normalize();
        }
    }

    /// The coded bytes. The always-zero first byte of the LZMA scheme is dropped, the final
    /// value is rounded to end in as many zero bytes as possible and those are dropped too
    /// (the decoder reads zeros past the end), at most [`MAX_DROPPED_ZEROS`] of them: a carry
    /// out of the rounding turns the pending run of 0xFF bytes into zeros as well, and that run
    /// can be longer than the decoder accepts to read past the end.
    pub(crate) fn finish(mut self) -> Vec<u8> {
        for k in (24..=32u32).rev() {
            let step = 1u64 << k;
            let v = (self.low + step - 1) & !(step - 1);
            if v < self.low + u64::from(self.range) {
                self.low = v;
                break;
            }
        }
        let before_flush = self.out.len();
        for _ in 0..5 {
            self.shift_low();
        }
        let mut out = self.out;
        let keep = before_flush.max(out.len().saturating_sub(MAX_DROPPED_ZEROS));
        while out.len() > keep && out.last() == Some(&0) {
            out.pop();
        }
        if out.first() == Some(&0) {
            out.remove(0);
        }
        out
    }
}

/// Reads bits back. Past the end of the data it reads zeros and counts them; the caller
/// rejects a stream that needed more than a few.
#[derive(Debug)]
pub(crate) struct Decoder<'a> {
    data: &'a [u8],
    pos: usize,
    range: u32,
    code: u32,
    overrun: usize,
}

impl<'a> Decoder<'a> {
    pub(crate) fn new(data: &'a [u8]) -> Self {
        let mut d = Self {
            data,
            pos: 0,
            range: u32::MAX,
            code: 0,
            overrun: 0,
        };
        for _ in 0..4 {
            d.code = (d.code << 8) | u32::from(d.next_byte());
        }
        d
    }

    fn next_byte(&mut self) -> u8 {
        match self.data.get(self.pos) {
            Some(&b) => {
                self.pos += 1;
                b
            }
            None => {
                self.overrun += 1;
                0
            }
        }
    }

    /// Bytes read past the end of the data so far.
    pub(crate) fn overrun(&self) -> usize {
        self.overrun
    }

    fn normalize(&mut self) {
        while self.range < TOP {
            self.range <<= 8;
            self.code = (self.code << 8) | u32::from(self.next_byte());
        }
    }

    pub(crate) fn bit(&mut self, p: &mut Bit) -> bool {
        let bound = (self.range >> PROB_BITS) * u32::from(p.p);
        let bit = if self.code < bound {
            self.range = bound;
            false
        } else {
            self.code -= bound;
            self.range -= bound;
            true
        };
        p.update(bit);
        self.normalize();
        bit
    }

    pub(crate) fn direct(&mut self, count: u32) -> u64 {
        let mut v = 0u64;
        for _ in 0..count {
            self.range >>= 1;
            let bit = self.code >= self.range;
            if bit {
                self.code -= self.range;
            }
            v = (v << 1) | u64::from(bit);
            self.normalize();
        }
        v
    }
}

/// An adaptive model of unsigned integers of one kind (angles, lengths, counts...).
#[derive(Debug, Clone)]
pub(crate) struct UintModel {
    length: [Bit; 128],
    first: [Bit; 65],
}

impl Default for UintModel {
    fn default() -> Self {
        Self {
            length: [Bit::default(); 128],
            first: [Bit::default(); 65],
        }
    }
}

/// Largest bit length (u64).
const MAX_LENGTH: u32 = 64;

impl UintModel {
    /// A model already adapted to bit lengths like `lengths` (a prior: it shortens the first
    /// values of each kind). Encoder and decoder build their models alike.
    pub(crate) fn primed(lengths: &[u32]) -> Self {
        let mut model = Self::default();
        for &len in lengths {
            let mut m = 1usize;
            for i in (0..7).rev() {
                let bit = (len >> i) & 1 == 1;
                model.length[m].update(bit);
                m = (m << 1) | usize::from(bit);
            }
        }
        model
    }

    pub(crate) fn encode(&mut self, e: &mut Encoder, n: u64) {
        let len = 64 - n.leading_zeros();
        let mut m = 1usize;
        for i in (0..7).rev() {
            let bit = (len >> i) & 1 == 1;
            e.bit(&mut self.length[m], bit);
            m = (m << 1) | usize::from(bit);
        }
        if len >= 2 {
            let rest = len - 1;
            let below = n & ((1u64 << rest) - 1);
            let first = (below >> (rest - 1)) & 1 == 1;
            e.bit(&mut self.first[len as usize], first);
            e.direct(below, rest - 1);
        }
    }

    /// `None` when the stream names an impossible bit length (a damaged link).
    pub(crate) fn decode(&mut self, d: &mut Decoder) -> Option<u64> {
        let mut m = 1usize;
        for _ in 0..7 {
            let bit = d.bit(&mut self.length[m]);
            m = (m << 1) | usize::from(bit);
        }
        let len = (m - 128) as u32;
        match len {
            0 => Some(0),
            1 => Some(1),
            l if l <= MAX_LENGTH => {
                let rest = l - 1;
                let first = u64::from(d.bit(&mut self.first[l as usize]));
                let low = d.direct(rest - 1);
                Some((1u64 << rest) | (first << (rest - 1)) | low)
            }
            _ => None,
        }
    }

    pub(crate) fn encode_signed(&mut self, e: &mut Encoder, v: i64) {
        self.encode(e, ((v << 1) ^ (v >> 63)) as u64);
    }

    pub(crate) fn decode_signed(&mut self, d: &mut Decoder) -> Option<i64> {
        let z = self.decode(d)?;
        Some(((z >> 1) as i64) ^ -((z & 1) as i64))
    }
}

/// An adaptive model of small symbols of `BITS` bits (a bit tree).
#[derive(Debug, Clone)]
pub(crate) struct SymbolModel<const N: usize> {
    probs: [Bit; N],
}

impl<const N: usize> Default for SymbolModel<N> {
    fn default() -> Self {
        Self {
            probs: [Bit::default(); N],
        }
    }
}

impl<const N: usize> SymbolModel<N> {
    /// Bits per symbol: N = 2^bits.
    const BITS: u32 = N.trailing_zeros();

    pub(crate) fn encode(&mut self, e: &mut Encoder, symbol: usize) {
        let mut m = 1usize;
        for i in (0..Self::BITS).rev() {
            let bit = (symbol >> i) & 1 == 1;
            e.bit(&mut self.probs[m], bit);
            m = (m << 1) | usize::from(bit);
        }
    }

    pub(crate) fn decode(&mut self, d: &mut Decoder) -> usize {
        let mut m = 1usize;
        for _ in 0..Self::BITS {
            let bit = d.bit(&mut self.probs[m]);
            m = (m << 1) | usize::from(bit);
        }
        m - N
    }
}

#[cfg(test)]
mod tests {
    #[cfg(target_arch = "wasm32")]
    use wasm_bindgen_test::wasm_bindgen_test as test;

    use super::*;

    #[test]
    fn integers_and_bits_round_trip() {
        let values: Vec<u64> = (0..2000u64)
            .map(|i| i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (i % 64))
            .chain([0, 1, 2, 3, u64::MAX, u64::MAX - 1, 1 << 63])
            .collect();
        let mut e = Encoder::new();
        let mut m = UintModel::default();
        let mut s = SymbolModel::<8>::default();
        let mut b = Bit::default();
        for (i, &v) in values.iter().enumerate() {
            m.encode(&mut e, v);
            m.encode_signed(&mut e, v as i64);
            s.encode(&mut e, i % 8);
            e.bit(&mut b, i % 3 == 0);
            e.direct(v, (i % 65) as u32);
        }
        let bytes = e.finish();
        let mut d = Decoder::new(&bytes);
        let mut m = UintModel::default();
        let mut s = SymbolModel::<8>::default();
        let mut b = Bit::default();
        for (i, &v) in values.iter().enumerate() {
            assert_eq!(m.decode(&mut d), Some(v), "value {i}");
            assert_eq!(m.decode_signed(&mut d), Some(v as i64));
            assert_eq!(s.decode(&mut d), i % 8);
            assert_eq!(d.bit(&mut b), i % 3 == 0);
            let c = (i % 65) as u32;
            let mask = if c == 64 { u64::MAX } else { (1u64 << c) - 1 };
            assert_eq!(d.direct(c), v & mask);
        }
        assert!(d.overrun() <= 5, "overrun {}", d.overrun());
    }

    #[test]
    fn an_empty_stream_is_empty() {
        assert!(Encoder::new().finish().is_empty());
    }
}

#[cfg(test)]
mod measure {
    #[cfg(target_arch = "wasm32")]
    use wasm_bindgen_test::wasm_bindgen_test as test;

    use super::*;

    /// Uniform angles in +-0.6 rad at 0.005 degrees hold log2(13751) = 13.75 bits each.
    #[test]
    fn uniform_angles_cost_less_than_half_a_bit_above_their_entropy() {
        let mut x: u64 = 12345;
        let mut e = Encoder::new();
        let mut m = UintModel::primed(&crate::link::ROTATION_PRIOR);
        let n = 216;
        for _ in 0..n {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (x >> 11) as f64 / (1u64 << 53) as f64;
            let q = ((u * 2.0 - 1.0) * 0.6 / (0.005f64.to_radians())).round() as i64;
            m.encode_signed(&mut e, q);
        }
        let b = e.finish();
        let bits = b.len() as f64 * 8.0 / n as f64;
        assert!(bits < 14.25, "{bits} bits per value");
    }
}
