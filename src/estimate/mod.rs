//! How good is an image, from the image alone: the error of each pixel's mean estimated from
//! **randomized replicates**, and the allocation of adaptive sampling's next round.
//!
//! # Why replicates
//!
//! For `n` independent samples the variance of their mean is `s²/n` (`s²` the sample
//! variance): what [`Film::variance_of_mean`] gives. Stratified and Sobol points are negatively
//! correlated, so for them `s²/n` overstates the error of the mean, by orders of magnitude where
//! the integrand is smooth (lit-checker with Sobol at 1024 spp). An estimate that holds for every
//! sampler renders `R` independent randomizations (seeds, hence scrambles and strata) of the
//! pixel, each a complete set of its own, and measures their spread: with replicate means `X_r`,
//! weights `W_r` (`Σ W_r = 1`) and the image's mean `F = Σ W_r X_r`,
//!
//! ```text
//!     Var(F) ≈ v̂ = Σ_r W_r (X_r − F)² / (R − 1)
//! ```
//!
//! which for equal weights is the textbook `Σ (X_r − F)² / (R (R − 1))`, an unbiased estimate
//! of `Var(F)` whatever the correlation inside a replicate. With unequal weights (a render
//! stopped between replicates' passes) it assumes `Var(X_r) ∝ 1/W_r`, exact for independent
//! samples and close otherwise. Per pixel it has only `R − 1` degrees of freedom (3 for the
//! default `R = 4`), but the image's estimated MSE and relMSE average it over every pixel and
//! channel. What it costs: each replicate is a stratified set of `N/R` samples instead of one
//! set of `N`, which loses what stratification gains between the sets (measured per sampler in
//! `docs/error.md`).
//!
//! The image's estimates are vrpt's metrics with `v̂` in place of the squared error: MSE
//! `mean(v̂)` and relMSE `mean(v̂/(r̃² + 0.01))` over pixels and channels, with `r̃²` an estimate
//! of the unknown `r²` from the neighbourhood ([`squared_reference`]).
//!
//! # Adaptive rounds, and why they are unbiased
//!
//! An adaptive render runs rounds `j = 0, 1, …`. In round `j` every replicate renders
//! `n_j(i) ≥ 1` samples of pixel `i` (the same count in every replicate), a fresh stratified set
//! of its own, and the round's replicate mean is `m_{j,r}(i)`. The counts `n_j` are decided from
//! rounds `< j` only ([`allocate`]). A pixel's replicate accumulates
//! `X_r = Σ_j b_j m_{j,r} / Σ_j b_j`, with `b_j` the round's *planned* average spp per pixel,
//! the same for every pixel and fixed before any sample is drawn. Given the rounds before it,
//! `m_{j,r}` is the mean of a set of `n_j ≥ 1` unbiased samples, so `E[m_{j,r} | rounds < j] = μ`
//! whatever `n_j` is; with weights that do not depend on the samples, `E[F] = Σ_j w_j μ = μ`
//! (a martingale sum). Weighting each round by the pixel's own count instead (the plain mean of
//! all its samples) would be biased: a pixel whose early samples came out high would get more
//! samples, which then dilute the high ones. The same argument makes `v̂` above unbiased for
//! `Var(F)`: `X_r − F` is a sum of martingale differences `w_j (m_{j,r} − m_j)`, whose cross
//! terms vanish in expectation. Stopping after a round chosen by the image's estimate (a
//! target error) or the clock makes the number of rounds random; the rule reads an average over
//! all pixels, so a pixel's own samples move it by about 1/pixels, which is neglected.

#![warn(missing_docs)]

use crate::film::Film;
use glam::{DVec3, Vec3};

mod allocation;

pub use allocation::{
    allocate, allocation_gains, cross_validated_gain, AllocationGains, ALLOCATE_ABOVE, MAX_SHARE,
    UNIFORM_SHARE,
};

/// ε of the relative error, as [`crate::analysis`]'s relMSE uses it: `(x − r)²/(r² + 0.01)`.
pub const REL_EPSILON: f64 = 0.01;

/// The replicates an image's mean is made of: per pixel and replicate, the weighted sum of the
/// replicate's means and its weight.
#[derive(Clone, Debug)]
pub struct Replicates {
    count: u32,
    pixels: usize,
    /// `Σ_j b_j m_{j,r}(i)` at `r·pixels + i` (a uniform render: the sum of its samples).
    sum: Vec<DVec3>,
    /// `Σ_j b_j` at `r·pixels + i` (a uniform render: its sample count).
    weight: Vec<f64>,
}

impl Replicates {
    /// `count` empty replicates of an image of `pixels` pixels.
    pub fn new(count: u32, pixels: usize) -> Self {
        let n = count.max(1) as usize * pixels;
        Replicates {
            count: count.max(1),
            pixels,
            sum: vec![DVec3::ZERO; n],
            weight: vec![0.0; n],
        }
    }

    /// The number of replicates.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Add `film`'s samples to replicate `r` (a pass of a uniform render: each sample weighs 1).
    pub fn add_samples(&mut self, r: u32, film: &Film) {
        let base = r as usize * self.pixels;
        for i in 0..self.pixels {
            let (s, _, n) = film.pixel_sums(i);
            self.sum[base + i] += s;
            self.weight[base + i] += n as f64;
        }
    }

    /// Add `film`'s per-pixel means to replicate `r` with weight `b` (a round of an adaptive
    /// render; `b` the round's planned spp, the same for every pixel). A pixel without samples
    /// adds nothing.
    pub fn add_means(&mut self, r: u32, film: &Film, b: f64) {
        let base = r as usize * self.pixels;
        for i in 0..self.pixels {
            if film.count(i) > 0 {
                self.sum[base + i] += b * film.mean(i);
                self.weight[base + i] += b;
            }
        }
    }

    /// How many replicates hold samples in every pixel.
    pub fn filled(&self) -> u32 {
        (0..self.count as usize)
            .filter(|&r| {
                self.weight[r * self.pixels..(r + 1) * self.pixels]
                    .iter()
                    .all(|&w| w > 0.0)
            })
            .count() as u32
    }

    /// Pixel `i`'s mean `F = Σ_r W_r X_r` (zero with no samples).
    pub fn mean(&self, i: usize) -> DVec3 {
        let (mut s, mut w) = (DVec3::ZERO, 0.0);
        for r in 0..self.count as usize {
            s += self.sum[r * self.pixels + i];
            w += self.weight[r * self.pixels + i];
        }
        if w > 0.0 {
            s / w
        } else {
            DVec3::ZERO
        }
    }

    /// The estimated variance of pixel `i`'s mean, `Σ_r W_r (X_r − F)²/(R′ − 1)` over the `R′`
    /// replicates that hold samples of it; `None` with fewer than two.
    pub fn variance_of_mean(&self, i: usize) -> Option<DVec3> {
        let f = self.mean(i);
        let (mut total, mut used, mut acc) = (0.0, 0u32, DVec3::ZERO);
        for r in 0..self.count as usize {
            let w = self.weight[r * self.pixels + i];
            if w > 0.0 {
                let d = self.sum[r * self.pixels + i] / w - f;
                acc += w * d * d;
                total += w;
                used += 1;
            }
        }
        (used >= 2).then(|| acc / (total * (used - 1) as f64))
    }
}

/// How an image's error was estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// From the spread of this many independent replicates.
    Replicates(u32),
    /// From the samples' variance, `s²/n`: exact for independent samples, an overestimate for
    /// stratified and Sobol ones (fewer than two replicates held samples).
    PerSample,
    /// No estimate: fewer than two replicates, and a pixel with fewer than two samples, whose
    /// variance one sample cannot tell (it is undefined, not zero). Its MSE and relMSE are NaN,
    /// so no target is ever reached on it.
    Undefined,
}

impl Method {
    /// As the metadata writes it: `replicates` or `per-sample`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Replicates(_) => "replicates",
            Method::PerSample => "per-sample",
            Method::Undefined => "undefined",
        }
    }
}

/// An image's estimated error: per pixel, and for the whole image.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorEstimate {
    /// How it was made.
    pub method: Method,
    /// The estimated variance of each pixel's mean, row-major.
    pub variance: Vec<Vec3>,
    /// `mean(v̂)` over pixels and channels: the estimated MSE against the true image.
    pub mse: f64,
    /// `mean(v̂/(F² + 0.01))`: the estimated relMSE.
    pub rel_mse: f64,
}

impl ErrorEstimate {
    /// The estimate of a `width`-wide image `mean` whose pixels' estimated variances are
    /// `variance`.
    pub fn new(method: Method, width: u32, mean: &[Vec3], variance: Vec<Vec3>) -> Self {
        let (mse, rel_mse) = image_error(width, mean, &variance);
        ErrorEstimate {
            method,
            variance,
            mse,
            rel_mse,
        }
    }

    /// From replicates where at least two hold samples of every pixel, else per sample from
    /// `film` where every pixel holds two samples or more, else [`Method::Undefined`].
    pub fn of(replicates: &Replicates, film: &Film) -> Self {
        let mean: Vec<Vec3> = (0..film.len()).map(|i| film.mean(i).as_vec3()).collect();
        if replicates.filled() >= 2 {
            let v = (0..film.len())
                .map(|i| replicates.variance_of_mean(i).unwrap_or_default().as_vec3())
                .collect();
            ErrorEstimate::new(
                Method::Replicates(replicates.filled()),
                film.width,
                &mean,
                v,
            )
        } else if (0..film.len()).all(|i| film.count(i) >= 2) {
            ErrorEstimate::new(Method::PerSample, film.width, &mean, film.variance_image())
        } else {
            ErrorEstimate {
                method: Method::Undefined,
                variance: vec![Vec3::NAN; film.len()],
                mse: f64::NAN,
                rel_mse: f64::NAN,
            }
        }
    }

    /// One line: the estimated relMSE and MSE, and how they were made.
    pub fn summary(&self) -> String {
        let how = match self.method {
            Method::Replicates(r) => format!("from {r} replicates"),
            Method::PerSample => {
                "per sample: s²/n of one set of points, an upper bound for stratified and Sobol \
                 points; --replicates 4 for an honest estimate"
                    .into()
            }
            Method::Undefined => {
                return "estimated error: undefined (a pixel holds fewer than two samples and \
                        there are fewer than two replicates)\n"
                    .into()
            }
        };
        format!(
            "estimated error: relMSE {:.4e}, MSE {:.4e} ({how})\n",
            self.rel_mse, self.mse
        )
    }
}

/// The estimated MSE and relMSE of a `width`-wide image from its pixels' estimated variances
/// (see [`squared_reference`] for the relMSE's denominator).
pub fn image_error(width: u32, mean: &[Vec3], variance: &[Vec3]) -> (f64, f64) {
    let n = (mean.len() * 3).max(1) as f64;
    let mse = (variance.iter())
        .map(|v| v.as_dvec3().element_sum())
        .sum::<f64>();
    let rel = rel_mse_against(&squared_reference(width, mean, variance), variance).0;
    (mse / n, rel)
}

/// The standard error of [`image_error`]'s relMSE: the spread of its terms `v̂/(r² + 0.01)` over
/// pixels and channels over `√(3·pixels)`. The terms differ from pixel to pixel in their true
/// values as well as by noise, so this overstates the noise of the estimate: a conservative
/// margin for deciding between two estimates, not a calibrated error.
pub fn rel_mse_standard_error(width: u32, mean: &[Vec3], variance: &[Vec3]) -> f64 {
    rel_mse_against(&squared_reference(width, mean, variance), variance).1
}

/// The relMSE `mean(v̂/(r² + 0.01))` of an image whose pixels' estimated variances are
/// `variance`, against squared references `r2` given per pixel and channel (so estimates of
/// several images can weigh their pixels alike), and its standard error as in
/// [`rel_mse_standard_error`].
pub fn rel_mse_against(r2: &[DVec3], variance: &[Vec3]) -> (f64, f64) {
    let terms = variance
        .iter()
        .zip(r2)
        .flat_map(|(v, r2)| (0..3).map(move |c| v[c] as f64 / (r2[c] + REL_EPSILON)));
    let (mut n, mut sum, mut sum_sq) = (0.0f64, 0.0f64, 0.0f64);
    for t in terms {
        n += 1.0;
        sum += t;
        sum_sq += t * t;
    }
    if n < 2.0 {
        return (sum / n.max(1.0), f64::INFINITY);
    }
    let var = ((sum_sq - sum * sum / n) / (n - 1.0)).max(0.0);
    (sum / n, (var / n).sqrt())
}

/// An estimate of each pixel's `r²` for the relMSE's denominator `r² + 0.01`, where the true
/// image `r` is unknown: per channel `λF² + (1 − λ)B²`, with `B` the 3×3 box average of the
/// mean `F` and `λ = F²/(F² + 16 v̂)`, so a pixel whose mean is already precise uses its own
/// value and a noisy one its neighbourhood's. Neither alone does: where samples are skewed, a
/// pixel whose samples came out high has a large `v̂` and a large `F²` together, so `v̂/F²`
/// underestimates the relMSE (2.2–2.5× on the Cornell box at 64 spp); the box average is nearly
/// independent of the pixel's noise but blurs what the image resolves (a checkerboard a few
/// pixels per square: lit-checker's estimate 3× high at 448 spp; glossy-plates' highlights 1.9×
/// low at 256 spp). The blend, against the true `r` at 64–256 spp: Cornell box 1.3–1.5× low,
/// glossy-plates 1.7× low.
pub fn squared_reference(width: u32, mean: &[Vec3], variance: &[Vec3]) -> Vec<DVec3> {
    let w = width.max(1) as usize;
    let h = mean.len() / w;
    let m: Vec<DVec3> = mean.iter().map(|m| m.as_dvec3()).collect();
    box3(w, h, &m)
        .into_iter()
        .zip(m.iter().zip(variance))
        .map(|(b, (f, v))| {
            let (f2, v) = (*f * *f, v.as_dvec3());
            let lambda = f2 / (f2 + 16.0 * v).max(DVec3::splat(1e-300));
            lambda * f2 + (DVec3::ONE - lambda) * b * b
        })
        .collect()
}

/// The 3×3 box average of a `w × h` map (fewer neighbours at the edges).
pub(crate) fn box3<T>(w: usize, h: usize, map: &[T]) -> Vec<T>
where
    T: Copy + Default + std::ops::Add<Output = T> + std::ops::Div<f64, Output = T>,
{
    let mut out = vec![T::default(); w * h];
    for y in 0..h {
        for x in 0..w {
            let (mut s, mut k) = (T::default(), 0.0);
            for yy in y.saturating_sub(1)..(y + 2).min(h) {
                for xx in x.saturating_sub(1)..(x + 2).min(w) {
                    s = s + map[yy * w + xx];
                    k += 1.0;
                }
            }
            out[y * w + x] = s / k;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replicate_spread_is_the_textbook_formula() {
        // one pixel, four replicates of two samples each: means 1, 2, 4, 7
        let mut reps = Replicates::new(4, 1);
        for (r, m) in [1.0f32, 2.0, 4.0, 7.0].into_iter().enumerate() {
            let mut f = Film::new(1, 1);
            let v = DVec3::splat(m as f64);
            f.add_pixel_sums(0, 2.0 * v, 2.0 * v * v, 2);
            reps.add_samples(r as u32, &f);
        }
        assert_eq!(reps.filled(), 4);
        assert!((reps.mean(0).x - 3.5).abs() < 1e-12);
        let want = [1.0, 2.0, 4.0, 7.0]
            .iter()
            .map(|m: &f64| (m - 3.5).powi(2))
            .sum::<f64>()
            / 12.0;
        assert!((reps.variance_of_mean(0).unwrap().x - want).abs() < 1e-12);
        // one replicate: no spread to measure
        let mut one = Replicates::new(4, 1);
        let mut f = Film::new(1, 1);
        f.add_pixel_sums(0, DVec3::ONE, DVec3::ONE, 1);
        one.add_samples(2, &f);
        assert_eq!((one.filled(), one.variance_of_mean(0)), (1, None));
    }

    #[test]
    fn rounds_weigh_by_plan_not_by_count() {
        // a round of 1 sample at weight 1 and one of 9 samples at weight 1: the mean is the
        // average of the two round means, not the mean of the ten samples
        let mut reps = Replicates::new(1, 1);
        let mut a = Film::new(1, 1);
        a.add_pixel_sums(0, DVec3::splat(10.0), DVec3::splat(100.0), 1);
        let mut b = Film::new(1, 1);
        b.add_pixel_sums(0, DVec3::splat(0.0), DVec3::ZERO, 9);
        reps.add_means(0, &a, 1.0);
        reps.add_means(0, &b, 1.0);
        assert!((reps.mean(0).x - 5.0).abs() < 1e-12);
    }
}
