//! What a render keeps of a path besides its radiance: nothing (an image's paths, which have
//! no recorder), or the path guide's training records ([`Training`], a [`PathRecorder`]).
//!
//! A training record of a guided bounce at `x` in direction `ωᵢ` (drawn with the mixture pdf
//! `p`) is the radiance that came back along it, `L_i ≈ ΔL/β` per channel (`ΔL` what the path
//! gathered after the bounce, `β` the throughput after it, before roulette), averaged over the
//! channels where `β` carries anything, divided by `p`, together with `L_i f cosθ` and the pdfs
//! (see [`crate::guiding`]). It goes to the S-tree leaf the spatial box filter picks around `x`,
//! jittered by a hash of the vertex and the direction: training only, so the image's samples
//! are untouched.

use crate::bsdf::BsdfSample;
use crate::guiding::{GuideAt, Record};
use glam::{Vec2, Vec3};

/// Bounces of a path whose radiance a training render records (the rest are not recorded).
pub const MAX_RECORDED_BOUNCES: usize = 16;

/// How a guided bounce's direction was drawn: its canonical point, and its BSDF and guide pdfs
/// (per solid angle).
#[derive(Clone, Copy, Debug)]
pub(super) struct Mixture {
    pub(super) point: Vec2,
    pub(super) p_bsdf: f32,
    pub(super) p_guide: f32,
}

/// What the path loop tells a recorder: each guided bounce as it is taken, and the path's
/// radiance at its end.
pub(super) trait PathRecorder {
    /// A guided bounce at `p` with guide `g`: drawn as `mix`, sampled as `bs`, the throughput
    /// after it `beta` (before roulette), the path's radiance so far `l`.
    fn bounce(&mut self, g: &GuideAt, p: Vec3, mix: &Mixture, bs: &BsdfSample, beta: Vec3, l: Vec3);
    /// The path ended with radiance `l`.
    fn finish(&mut self, l: Vec3);
}

/// A bounce whose record waits for the rest of the path.
#[derive(Clone, Copy, Debug, Default)]
struct Pending {
    leaf: u32,
    point: Vec2,
    /// The throughput after the bounce: `β·f·cosθ/p` (before Russian roulette).
    beta: Vec3,
    /// The path's radiance when the bounce's record starts counting.
    l_start: Vec3,
    /// `f·cosθ` of the direction.
    f_cos: Vec3,
    /// The direction's (mixture) pdf, and its BSDF and guide pdfs.
    pdf: f32,
    p_bsdf: f32,
    p_guide: f32,
}

/// Keeps a training iteration's records: the first [`MAX_RECORDED_BOUNCES`] guided bounces of
/// the path wait for its end, then go to `out` in bounce order.
pub(super) struct Training<'a> {
    out: &'a mut Vec<Record>,
    pending: [Pending; MAX_RECORDED_BOUNCES],
    n: usize,
}

impl<'a> Training<'a> {
    pub(super) fn new(out: &'a mut Vec<Record>) -> Self {
        Training {
            out,
            pending: [Pending::default(); MAX_RECORDED_BOUNCES],
            n: 0,
        }
    }
}

impl PathRecorder for Training<'_> {
    fn bounce(
        &mut self,
        g: &GuideAt,
        p: Vec3,
        mix: &Mixture,
        bs: &BsdfSample,
        beta: Vec3,
        l: Vec3,
    ) {
        if self.n >= MAX_RECORDED_BOUNCES {
            return;
        }
        let c = mix.point;
        let h = crate::math::hash_words(&[
            p.x.to_bits() as u64 | (p.y.to_bits() as u64) << 32,
            p.z.to_bits() as u64 | (c.x.to_bits() as u64) << 32,
            c.y.to_bits() as u64,
        ]);
        let jitter = Vec3::new(
            crate::math::u64_to_unit_f32(h),
            crate::math::u64_to_unit_f32(crate::math::mix64(h ^ 1)),
            crate::math::u64_to_unit_f32(crate::math::mix64(h ^ 2)),
        );
        self.pending[self.n] = Pending {
            leaf: g.splat_leaf(p, jitter),
            point: c,
            beta,
            l_start: l,
            f_cos: bs.f * bs.wi.z,
            pdf: bs.pdf,
            p_bsdf: mix.p_bsdf,
            p_guide: mix.p_guide,
        };
        self.n += 1;
    }

    fn finish(&mut self, l: Vec3) {
        for v in &self.pending[..self.n] {
            // L_i ≈ ΔL / β per channel (where β carries anything), averaged over the channels
            // (divided by the channels that carry something: by 3 always, a bounce after a
            // saturated colour learned ⅓ or ⅔ of its radiance)
            let d = l - v.l_start;
            let (mut li, mut product, mut channels) = (0.0, 0.0, 0.0f32);
            for c in 0..3 {
                if v.beta[c] > 1e-12 {
                    let lc = d[c] / v.beta[c];
                    li += lc;
                    product += lc * v.f_cos[c];
                    channels += 1.0;
                }
            }
            let channels = channels.max(1.0); // none: a record of 0, as before
            let value = li / (channels * v.pdf);
            if value.is_finite() && value >= 0.0 {
                self.out.push(Record {
                    leaf: v.leaf,
                    point: v.point,
                    value,
                    product: product / channels,
                    pdf: v.pdf,
                    p_bsdf: v.p_bsdf,
                    p_guide: v.p_guide,
                });
            }
        }
        self.n = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record is `ΔL/β` averaged over the channels β carries: after a bounce off a pure red
    /// surface (β = (0.5, 0, 0)) that brought back red light 1, the radiance that arrived is 2,
    /// and the record 2/p, not ⅓ of it (issue 46: the sum was divided by 3 whatever the count).
    #[test]
    fn a_record_averages_over_the_channels_that_carry_light() {
        let mut out = Vec::new();
        let mut t = Training::new(&mut out);
        for (k, beta) in [
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::splat(0.5),
        ]
        .into_iter()
        .enumerate()
        {
            t.pending[k] = Pending {
                beta,
                f_cos: Vec3::splat(0.25),
                pdf: 4.0,
                ..Pending::default()
            };
        }
        t.n = 3;
        t.finish(Vec3::new(1.0, 1.0, 0.0));
        // red only: 2/4; red and green: (2 + 2)/2/4; all three: (2 + 2 + 0)/3/4
        let want = [0.5, 0.5, 1.0 / 3.0];
        for (r, w) in out.iter().zip(want) {
            assert!((r.value - w).abs() < 1e-6, "{} against {w}", r.value);
            assert!((r.product - 4.0 * w * 0.25).abs() < 1e-6);
        }
        assert_eq!(out.len(), 3);
    }
}
