//! A guided render's training iterations kept in its image: the final iteration and the last
//! [`KEPT_ITERATIONS`] training iterations combined by inverse variance (issue 51; Müller 2019,
//! "Practical Path Guiding in Production", §"inverse-variance-based sample combination").
//!
//! **The estimator.** Each group `g` (a kept training iteration, or the final iteration) gives
//! at pixel `p` the mean `m_g(p)` of its `n_g(p)` samples, an unbiased estimate of the pixel
//! given the guide it sampled with, and the estimated variance of that mean `v_g(p) = s²_g/n_g`.
//! The image is `m(p) = Σ_g w_g m_g(p)` with `w_g = a_g / Σ_h a_h`, `a_g = 1/V_g`, where `V_g` is
//! group `g`'s estimated relMSE, `mean(v_g(p)/(F(p)² + 0.01))` over pixels and channels (`F`:
//! the pixel's samples of all groups pooled, the same denominator for every group, so the
//! weights compare the groups' noise and nothing else). Weights that sum to one and do not
//! depend on the means they weigh keep the image unbiased; inverse variance is the choice that
//! minimises the combination's variance `Σ_g w_g² v_g(p)` when the `V_g` are in proportion to
//! the pixels' variances.
//!
//! **Weights from the other half.** The tiles are two classes in a checkerboard (tile `(i, j)`
//! in class `(i + j) mod 2`), and the pixels of one class are weighted by the `V_g` measured over
//! the other class. Given the guides, the two classes' samples are independent (a path, reused
//! or not, stays in its tile), so a pixel's weights do not depend on its own samples. With
//! weights from the whole image, a firefly would raise its pixel and lower its own group's
//! weight together: an image biased toward the dark wherever one sample can move `V_g`. What
//! remains: a pixel's training samples taught the guide that the other class's later
//! iterations sampled with, so its weights depend on them through the guide (a second-order
//! effect, below what the region z-tests of guided renders can see). An image of one tile has
//! no other half and weighs by its own `V_g`.
//!
//! **Which iterations.** The last [`KEPT_ITERATIONS`]: with iterations of doubling spp they hold
//! 15/16 of the training's samples, each kept one costs 28 bytes a pixel, and the earlier ones,
//! sampled with the least-trained guides, weigh little. A group contributes at a pixel where it
//! holds at least two samples (its variance is known), so the first iteration, of one sample,
//! never does. A class where some `V_g` is not positive and finite (a black image) weighs its
//! groups by their samples instead.
//!
//! **The film.** Each pixel's sums are rewritten so that the film's mean is `m(p)` and its
//! variance of the mean is `Σ_g w_g² v_g(p)`, with the count `N = Σ_g n_g(p)`, the samples
//! behind it: `Σx = N·m`, `Σx² = N(N − 1)·v + N·m²`. Films so written merge as renders of `N`
//! samples each; the error estimate read from the film is the combination's.

use crate::film::Film;
use glam::{DVec3, Vec3};
use std::collections::VecDeque;

use super::TILE;

/// Training iterations kept for the image: the last ones.
pub const KEPT_ITERATIONS: usize = 4;

/// Bytes a pixel each kept iteration holds: mean and variance (f32 × 3 each) and a count.
pub const KEPT_BYTES_PER_PIXEL: u64 = 28;

/// One iteration's image: per pixel the mean, the variance of the mean and the samples.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct IterationImage {
    mean: Vec<Vec3>,
    variance: Vec<Vec3>,
    count: Vec<u32>,
}

impl IterationImage {
    /// The image of `film`'s sums.
    pub(super) fn of(film: &Film) -> Self {
        IterationImage {
            mean: film.mean_image(),
            variance: film.variance_image(),
            count: film.sample_counts(),
        }
    }
}

/// The training iterations kept so far, the oldest dropped past [`KEPT_ITERATIONS`], and the
/// gate's probes ([`super::gate`]: at most [`super::gate::GATE_PROBES`], all kept).
#[derive(Debug, Default)]
pub(super) struct KeptIterations {
    images: VecDeque<IterationImage>,
    probes: Vec<IterationImage>,
}

impl KeptIterations {
    /// Keep an iteration's image.
    pub(super) fn push(&mut self, image: IterationImage) {
        if self.images.len() == KEPT_ITERATIONS {
            self.images.pop_front();
        }
        self.images.push_back(image);
    }

    /// Keep a probe of the gate.
    pub(super) fn push_probe(&mut self, probe: IterationImage) {
        self.probes.push(probe);
    }

    /// The kept iterations, oldest first, then the probes.
    pub(super) fn images(&self) -> impl Iterator<Item = &IterationImage> {
        self.images.iter().chain(&self.probes)
    }

    /// Combine the final iteration's sums in `film` with what is kept ([`combine`]): the
    /// training iterations, and the gate's probes where it `closed`. An open gate's probes are
    /// dropped: Phong images where the guide wins have heavier tails than the guided ones,
    /// their variances read low at a few samples per pixel, and kept they cost the gap 1.46×
    /// in relMSE at 10 s against the render without the gate (two seed pairs).
    pub(super) fn combine_into(mut self, film: &mut Film, closed: bool) -> Combination {
        if !closed {
            self.probes.clear();
        }
        let images: Vec<&IterationImage> = self.images().collect();
        Combination {
            probes: self.probes.len() as u32,
            ..combine(film, &images)
        }
    }
}

/// What the combination of a guided render's training images did (`render::combine`): the
/// training iterations that hold samples in the image, and the final iteration's weight
/// (averaged over the image's pixels).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Combination {
    /// Training images combined with the final iteration: training iterations and the gate's
    /// probes ([`super::gate`]).
    pub iterations: u32,
    /// Of them, the gate's probes.
    pub probes: u32,
    /// The final iteration's weight `w_final`, the mean over pixels.
    pub final_weight: f64,
}

/// The relMSE's `ε` ([`crate::estimate`]'s).
const EPSILON: f64 = 0.01;

/// The checkerboard class (0 or 1) of pixel `i` of a `width`-wide image.
fn class(i: usize, width: u32) -> usize {
    let (x, y) = (i as u32 % width, i as u32 / width);
    ((x / TILE + y / TILE) % 2) as usize
}

/// Combine the final iteration's sums in `film` with the training iterations `kept` (same size,
/// oldest first) by inverse variance, as the module doc says, writing the combination into
/// `film`. With nothing kept the film is left as it is.
pub(super) fn combine(film: &mut Film, kept: &[&IterationImage]) -> Combination {
    if kept.is_empty() {
        return Combination {
            iterations: 0,
            probes: 0,
            final_weight: 1.0,
        };
    }
    let last = IterationImage::of(film);
    let groups: Vec<&IterationImage> = kept.iter().copied().chain([&last]).collect();
    let (n_pixels, width) = (film.len(), film.width);
    // F(p): every group's samples of the pixel pooled
    let pooled = pooled(&groups);
    // per group and class: Σ v/(F² + ε) over pixels and channels, the terms, and the samples
    let mut rel = vec![[0.0f64; 2]; groups.len()];
    let mut terms = vec![[0u64; 2]; groups.len()];
    let mut samples = vec![[0.0f64; 2]; groups.len()];
    for (i, f) in pooled.iter().enumerate() {
        let c = class(i, width);
        for (k, g) in groups.iter().enumerate() {
            samples[k][c] += g.count[i] as f64;
            if g.count[i] >= 2 {
                let v = g.variance[i].as_dvec3();
                rel[k][c] += (v / (*f * *f + DVec3::splat(EPSILON))).element_sum();
                terms[k][c] += 3;
            }
        }
    }
    let weights = class_weights(&rel, &terms, &samples);
    let mut final_weight = 0.0;
    for i in 0..n_pixels {
        let a = &weights[class(i, width)];
        let (mut sum_a, mut m, mut v, mut n) = (0.0, DVec3::ZERO, DVec3::ZERO, 0u64);
        for (k, g) in groups.iter().enumerate() {
            if g.count[i] >= 2 {
                sum_a += a[k];
                m += a[k] * g.mean[i].as_dvec3();
                v += a[k] * a[k] * g.variance[i].as_dvec3();
                n += g.count[i] as u64;
            }
        }
        if sum_a <= 0.0 {
            final_weight += 1.0;
            continue; // no group with a variance here: the final iteration's sums stay
        }
        if last.count[i] >= 2 {
            final_weight += a[groups.len() - 1] / sum_a;
        }
        let (m, v) = (m / sum_a, v / (sum_a * sum_a));
        let nf = n as f64;
        film.set_pixel_sums(i, nf * m, nf * (nf - 1.0) * v + nf * m * m, n);
    }
    Combination {
        iterations: kept.len() as u32,
        probes: 0,
        final_weight: final_weight / n_pixels.max(1) as f64,
    }
}

/// Each pixel's mean over every image's samples of it pooled (0 where none has any).
fn pooled(images: &[&IterationImage]) -> Vec<DVec3> {
    let n_pixels = images.first().map_or(0, |g| g.mean.len());
    (0..n_pixels)
        .map(|i| {
            let (mut s, mut n) = (DVec3::ZERO, 0.0);
            for g in images {
                s += g.mean[i].as_dvec3() * g.count[i] as f64;
                n += g.count[i] as f64;
            }
            if n > 0.0 {
                s / n
            } else {
                DVec3::ZERO
            }
        })
        .collect()
}

/// Each image's terms of the relative variance of the mean against one denominator for all,
/// aligned: per pixel (those holding at least two samples in every image) and channel,
/// `v_g(p)/(F̄(p)² + ε)`, with `F̄` the images' samples pooled per pixel and then averaged
/// over the box of `2·blur + 1` pixels a side about `p` (cut at the image's border). `width`:
/// the images'.
pub(super) fn shared_rel_terms(
    images: &[&IterationImage],
    width: usize,
    blur: usize,
) -> Vec<Vec<f64>> {
    let n_pixels = images.first().map_or(0, |g| g.mean.len());
    let height = n_pixels / width.max(1);
    let pooled = pooled(images);
    let mut terms = vec![Vec::with_capacity(3 * n_pixels); images.len()];
    for i in 0..n_pixels {
        if images.iter().any(|g| g.count[i] < 2) {
            continue;
        }
        let (x, y) = (i % width, i / width);
        let (mut f, mut n) = (DVec3::ZERO, 0.0);
        for yy in y.saturating_sub(blur)..=(y + blur).min(height - 1) {
            for xx in x.saturating_sub(blur)..=(x + blur).min(width - 1) {
                f += pooled[yy * width + xx];
                n += 1.0;
            }
        }
        let f = f / n;
        let d = f * f + DVec3::splat(EPSILON);
        for (k, g) in images.iter().enumerate() {
            terms[k].extend((g.variance[i].as_dvec3() / d).to_array());
        }
    }
    terms
}

/// `a_g` for the pixels of each class, from the other class's `V_g` (its own where the other
/// class has no terms for some group): `1/V_g`, or the groups' samples where some `V_g` is not
/// positive and finite. `rel`, `terms` and `samples` are per group and class: `Σ v/(F² + ε)`,
/// its terms, and the samples.
fn class_weights(rel: &[[f64; 2]], terms: &[[u64; 2]], samples: &[[f64; 2]]) -> [Vec<f64>; 2] {
    [0, 1].map(|c| {
        let o = if terms.iter().all(|t| t[1 - c] > 0) {
            1 - c
        } else {
            c
        };
        let inverse: Vec<f64> = (0..rel.len())
            .map(|k| 1.0 / (rel[k][o] / terms[k][o].max(1) as f64))
            .collect();
        if inverse.iter().all(|a| a.is_finite() && *a > 0.0) {
            inverse
        } else {
            samples.iter().map(|s| s[o]).collect()
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A film of `w × h` pixels whose pixel `i` holds `n` samples: `n/2` at `value(i) − d` and
    /// `n/2` at `value(i) + d` (mean `value(i)`, sample variance `d²·n/(n−1)`).
    fn film(w: u32, h: u32, n: u64, d: f64, value: impl Fn(usize) -> f64) -> Film {
        let mut f = Film::new(w, h);
        for i in 0..f.len() {
            let (lo, hi) = (value(i) - d, value(i) + d);
            let half = (n / 2) as f64;
            f.add_pixel_sums(
                i,
                DVec3::splat(half * (lo + hi)),
                DVec3::splat(half * (lo * lo + hi * hi)),
                n,
            );
        }
        f
    }

    /// Groups of equal value combine to that value whatever their weights (the weights sum to
    /// one), the count is the samples of all, and the weights are inverse variance: a training
    /// iteration with 4× the final's variance of the mean weighs 1/5, and the combination's
    /// variance is `0.8²·v + 0.2²·4v = 0.8 v`.
    #[test]
    fn equal_groups_keep_their_value_and_weigh_by_inverse_variance() {
        let (w, h) = (48, 32);
        let value = |i: usize| 0.5 + (i % 7) as f64;
        let training = film(w, h, 16, 2.0, value);
        let mut last = film(w, h, 16, 1.0, value);
        let v_last = last.variance_of_mean(5).x;
        let v_train = IterationImage::of(&training).variance[5].x as f64;
        assert!((v_train / v_last - 4.0).abs() < 1e-6);
        let kept = IterationImage::of(&training);
        // the same value everywhere, so every pixel's relMSE term scales alike: weights 1/5, 4/5
        let c = combine(&mut last, &[&kept]);
        assert_eq!(c.iterations, 1);
        assert!((c.final_weight - 0.8).abs() < 1e-6, "{c:?}");
        for i in 0..last.len() {
            assert!((last.mean(i).x - value(i)).abs() < 1e-5 * value(i));
            assert_eq!(last.count(i), 32);
            let expect = 0.64 * v_last + 0.04 * 4.0 * v_last;
            assert!((last.variance_of_mean(i).x / expect - 1.0).abs() < 1e-5);
        }
    }

    /// A pixel's weights come from the other class of tiles: a firefly in one pixel of the final
    /// iteration changes the weights of the other class's pixels, not its own class's, so its
    /// own pixel is combined with the weights it would have had without it.
    #[test]
    fn a_pixels_weights_do_not_see_its_own_samples() {
        let (w, h) = (64, 32); // 4 × 2 tiles, both classes
        let kept = IterationImage::of(&film(w, h, 8, 1.0, |_| 1.0));
        let last = film(w, h, 32, 1.0, |_| 1.0);
        let mut calm = last.clone();
        combine(&mut calm, &[&kept]);
        let mut loud = last.clone();
        let at = loud.index(3, 3); // tile (0, 0): class 0
        loud.add_pixel_sums(at, DVec3::splat(1e4), DVec3::splat(1e8), 0);
        let final_mean = loud.mean(at).x;
        combine(&mut loud, &[&kept]);
        // the firefly's class: every other pixel as without it, bit for bit
        let same_class = loud.index(20, 20); // tile (1, 1)
        assert_eq!(loud.pixel_sums(same_class), calm.pixel_sums(same_class));
        // the other class weighs the final iteration less now
        let other_class = loud.index(20, 3); // tile (1, 0)
        assert_ne!(loud.pixel_sums(other_class), calm.pixel_sums(other_class));
        // the firefly's pixel: class 0's weights, read off a probe pixel of class 0 whose final
        // mean is 1 and training mean 0 (same variances), so its combination is w_final
        let mut probe = last.clone();
        let mut zero = kept.clone();
        let p = probe.index(5, 5);
        zero.mean[p] = Vec3::ZERO;
        combine(&mut probe, &[&zero]);
        let w_final = probe.mean(p).x;
        assert!(w_final > 0.5 && w_final < 1.0, "{w_final}");
        let expect = w_final * final_mean + (1.0 - w_final) * kept.mean[at].x as f64;
        assert!((loud.mean(at).x / expect - 1.0).abs() < 1e-5);
    }
}
