//! Small math helpers: an orthonormal frame about a normal, integer hashing, and `atan2`.
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

/// Coefficients of `atan(t)/t ≈ Σ c_k t^(2k)` on `t ∈ [0, 1]`: a near-minimax fit (least
/// squares at Chebyshev nodes, reweighted toward the largest error), absolute error 6e-9 in
/// exact arithmetic, 1.0e-7 evaluated in `f32` (two ulps of π/4).
const ATAN: [f32; 9] = [
    0.999_999_9,
    -0.333_326,
    0.199_859_07,
    -0.141_612_29,
    0.104_989_46,
    -0.072_348_58,
    0.039_781_23,
    -0.014_401_361,
    0.002_456_725_3,
];

/// `atan2(y, x)` in `[−π, π]`, within 4e-7 rad of the exact value (libm's `atan2f`, the
/// exact value rounded, is within 1.2e-7 at |φ| near π; 4e-7 is 6e-8 of the guide's
/// canonical `φ/2π`, a sixteenth of its finest cell, 2⁻²⁰): the angle of the smaller of `|x|`,
/// `|y|` over the larger by a polynomial (`ATAN`), then reflected into its octant, with no
/// branch on the data. `(0, 0)` gives `±0`. The guide's mapping of each direction it
/// evaluates or records takes one ([`crate::guiding::dir_to_canonical`]): with it the mapping
/// runs 1.46× as fast as with `f32::atan2` (`cargo bench --bench sampling -- guide/`, 76 →
/// 112 M/s; a direction's guide pdf 41 → 58 M/s; 2-core EPYC), and a guided render of
/// Mitsuba's box 1.02× (1 thread, 16 spp, 6 of 6 seeds faster, 3.68 → 3.76 M rays/s).
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    // 0/0 is the one NaN: (0, 0) gives 0 over the least positive number
    let t = lo / hi.max(f32::MIN_POSITIVE);
    // Estrin's scheme: four independent pairs, then their combination by z², z⁴, z⁸, for a
    // short chain of dependent operations (the guide's descent waits on this angle)
    let z = t * t;
    let (z2, c) = (z * z, &ATAN);
    let z4 = z2 * z2;
    let (p01, p23) = (c[0] + c[1] * z, c[2] + c[3] * z);
    let (p45, p67) = (c[4] + c[5] * z, c[6] + c[7] * z);
    let p = (p01 + p23 * z2) + (p45 + p67 * z2) * z4 + c[8] * (z4 * z4);
    // the reflections `r → π/2 − r` and `r → π − r` as `c·a + (1 − 2c)·r` with `c` 0 or 1:
    // no branch for the octant, random for the guide's directions (each `if` a misprediction
    // half the time, which took more than the polynomial); with `c` 0, `r` is unchanged
    let reflect = |r: f32, c: bool, a: f32| {
        let c = c as u8 as f32;
        c * a + (1.0 - 2.0 * c) * r
    };
    let r = reflect(p * t, ay > ax, std::f32::consts::FRAC_PI_2);
    reflect(r, x < 0.0, std::f32::consts::PI).copysign(y)
}

/// `(sin x, cos x)` for `|x| ≤ π/4` by Cephes' `sinf` and `cosf` polynomials (Moshier 1989:
/// `x + x³·P(x²)` and `1 − x²/2 + x⁴·Q(x²)`, fitted on that interval), each value within two
/// ulps of the exact one; no range reduction, which the callers' angles do not need. The
/// concentric disk map's angle is in that range ([`crate::sampling::sample_concentric_disk`]):
/// libm's `sincosf` reduces any angle first, and was 2.6% of a render of Mitsuba's box.
#[inline(always)]
pub fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let z = x * x;
    let s = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * x + x;
    let c = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (s, c)
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

    /// [`atan2`] against the exact angle (f64) at every octant, the axes and the signed zeros:
    /// within 4e-7 rad: the fit's 1.0e-7, f32 π's own 0.9e-7 and two roundings (the
    /// reflection's, the polynomial's last) of up to 1.2e-7 each; the worst seen is 3.1e-7.
    #[test]
    fn atan2_is_within_four_tenths_of_a_microradian() {
        let mut worst = 0.0f64;
        let n = 20_000;
        for i in 0..n {
            let a = (i as f64 + 0.5) / n as f64 * std::f64::consts::TAU - std::f64::consts::PI;
            for r in [1e-3f64, 0.7, 1.0, 3e4] {
                let (y, x) = ((r * a.sin()) as f32, (r * a.cos()) as f32);
                let exact = (y as f64).atan2(x as f64);
                worst = worst.max((atan2(y, x) as f64 - exact).abs());
            }
        }
        assert!(worst < 4e-7, "{worst}");
        for (y, x) in [
            (0.0f32, 1.0f32),
            (1.0, 0.0),
            (0.0, -1.0),
            (-1.0, 0.0),
            (1.0, 1.0),
        ] {
            let exact = (y as f64).atan2(x as f64);
            assert!((atan2(y, x) as f64 - exact).abs() < 4e-7, "{y} {x}");
        }
        assert_eq!(atan2(0.0, 0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(atan2(-0.0, 1.0).to_bits(), (-0.0f32).to_bits());
        assert!((atan2(-1e-30, -1.0) + std::f32::consts::PI).abs() < 4e-7);
    }

    /// [`sin_cos_quarter`] against the exact values (f64) on a grid of 2²⁰ + 1 angles over
    /// `[−π/4, π/4]` and at its ends and zeros: within 1.2e-7 (two ulps of the largest value,
    /// `cos 0 = 1`, whose ulp below is 6e-8; Cephes' fits are within about one ulp, the
    /// evaluation's roundings add one), and `sin` keeps the sign of `x`.
    #[test]
    fn sin_cos_quarter_is_within_two_ulps() {
        let quarter = std::f32::consts::FRAC_PI_4;
        let n = 1 << 20;
        let mut worst = 0.0f64;
        for i in 0..=n {
            let x = -quarter + 2.0 * quarter * (i as f32 / n as f32);
            for x in [x, quarter, -quarter, 0.0, -0.0, 1e-20] {
                let (s, c) = sin_cos_quarter(x);
                let (es, ec) = (x as f64).sin_cos();
                worst = worst.max((s as f64 - es).abs()).max((c as f64 - ec).abs());
                assert!(s == 0.0 || s.signum() == x.signum(), "{x}: {s}");
            }
        }
        assert!(worst < 1.2e-7, "worst error {worst:e}");
        assert_eq!(sin_cos_quarter(0.0), (0.0, 1.0));
    }
}
