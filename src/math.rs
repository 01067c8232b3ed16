//! Small math helpers: an orthonormal frame about a normal, and integer hashing.
//!
//! [`Frame`] turns world vectors into the local shading frame (z = normal) and back; it is built
//! with the branchless construction of Duff et al. 2017 ("Building an orthonormal basis,
//! revisited"). The hashes are the 64-bit finalizer of SplitMix64 / MurmurHash3: bijective,
//! avalanching mixes used to key every random number by (seed, pixel, sample, dimension).

use glam::Vec3;

/// An orthonormal basis `(s, t, n)`; local coordinates have z along `n`.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// A right-handed frame with `n` (unit length) as its z axis.
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// World → local (z = normal).
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local → world.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Mirror `w` about the z axis of the local frame: `2 (w·z) z − w`.
#[inline]
pub fn reflect_local(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// The SplitMix64 finalizer: a bijective avalanche mix of 64 bits.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Hash of several words, order-sensitive.
#[inline]
pub fn hash_words(words: &[u64]) -> u64 {
    let mut h = WordHash::default();
    h.extend(words.iter().copied());
    h.finish()
}

/// [`hash_words`] fed a word at a time (the same value for the same words), so a long sequence
/// (every texel of a texture) needs no buffer.
#[derive(Clone, Copy, Debug)]
pub struct WordHash(u64);

impl Default for WordHash {
    fn default() -> Self {
        WordHash(0x9e37_79b9_7f4a_7c15)
    }
}

impl WordHash {
    /// Add one word.
    #[inline]
    pub fn push(&mut self, w: u64) {
        self.0 = mix64(self.0 ^ w.wrapping_add(0x9e37_79b9_7f4a_7c15));
    }

    /// The hash of the words so far.
    pub fn finish(&self) -> u64 {
        self.0
    }
}

impl Extend<u64> for WordHash {
    fn extend<I: IntoIterator<Item = u64>>(&mut self, words: I) {
        for w in words {
            self.push(w);
        }
    }
}

/// The top 24 bits of a hash as a float in [0, 1): every value exactly representable.
#[inline]
pub fn u64_to_unit_f32(h: u64) -> f32 {
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// Mean of the three channels.
#[inline]
pub fn average(v: Vec3) -> f32 {
    (v.x + v.y + v.z) * (1.0 / 3.0)
}

/// Luminance (Rec. 709 weights) of linear RGB.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_round_trips() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.5, 0.2).normalize(),
            Vec3::new(1e-4, 1e-4, -1.0).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!(f.s.dot(f.t).abs() < 1e-5 && f.s.dot(f.n).abs() < 1e-5);
            assert!(f.t.dot(f.n).abs() < 1e-5);
            assert!((f.s.length() - 1.0).abs() < 1e-5 && (f.t.length() - 1.0).abs() < 1e-5);
            let v = Vec3::new(0.2, 0.7, -0.4);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
            assert!((f.to_local(n) - Vec3::Z).length() < 1e-5);
        }
    }

    #[test]
    fn unit_float_is_in_range() {
        assert_eq!(u64_to_unit_f32(0), 0.0);
        assert!(u64_to_unit_f32(u64::MAX) < 1.0);
    }
}
