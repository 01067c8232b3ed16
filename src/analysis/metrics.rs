//! Error metrics of an image `x` against a reference `r`, averaged over pixels and the three
//! channels (images are row-major `Vec3`s of the same size):
//!
//! - MSE `mean((x − r)²)`, RMSE `√MSE`, MAE `mean(|x − r|)`, mean signed error `mean(x − r)`;
//! - relative MSE `mean((x − r)² / (r² + ε))` with `ε = 0.01` ([`REL_EPSILON`]), so dark pixels
//!   count without dividing by zero;
//! - over K independent runs of the same estimator: the per-pixel variance of one run (the
//!   sample variance across runs, averaged over pixels), and the bias test: each run's mean
//!   signed error `e_k` is an average over all pixels, so nearly normal; `t = ē / (s_e/√K)` is
//!   Student-t with K − 1 degrees of freedom when the estimator is unbiased (the reference's own
//!   error is a constant shift shared by all runs, negligible when its spp ≫ K·spp);
//! - per-pixel bias z-scores of a mean image with known variance against a reference with known
//!   variance: `z = (m − r)/√(v_m + v_r)`;
//! - the relMSE of one render estimated from a pair of independent renders `a`, `b` of the same
//!   estimator, without a converged reference ([`pair_rel_mse`]).

use crate::stats::student_t_two_sided_p;
use glam::Vec3;

/// ε of the relative MSE.
pub const REL_EPSILON: f64 = 0.01;

/// Error metrics of one image against a reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// Mean squared error over pixels and channels.
    pub mse: f64,
    /// Relative MSE, `mean((x − r)²/(r² + 0.01))`.
    pub rel_mse: f64,
    /// Root of the MSE.
    pub rmse: f64,
    /// Mean absolute error.
    pub mae: f64,
    /// Mean of `x − r` (the sign of a bias).
    pub mean_signed_error: f64,
}

fn check_sizes(a: &[Vec3], b: &[Vec3]) {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    assert!(!a.is_empty(), "empty image");
}

/// MSE, relMSE, RMSE, MAE and mean signed error of `image` against `reference`.
pub fn metrics(image: &[Vec3], reference: &[Vec3]) -> Metrics {
    check_sizes(image, reference);
    let (mut se, mut rel, mut ae, mut signed) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (x, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let (x, r) = (x[c] as f64, r[c] as f64);
            let d = x - r;
            se += d * d;
            rel += d * d / (r * r + REL_EPSILON);
            ae += d.abs();
            signed += d;
        }
    }
    let n = (image.len() * 3) as f64;
    Metrics {
        mse: se / n,
        rel_mse: rel / n,
        rmse: (se / n).sqrt(),
        mae: ae / n,
        mean_signed_error: signed / n,
    }
}

/// The relMSE of one render estimated from two independent unbiased renders `a` and `b` of
/// the same estimator, the relMSE's `r²` taken from `c`, an estimate of the true image
/// independent of both: `mean((a − b)²/(2·(c² + ε)))` over pixels and channels.
///
/// Per pixel of value `r` and variance `v` (of one render), `E[(a − b)²] = 2v`, so the numerator
/// over 2 estimates the `v` of the relMSE's term `v/(r² + ε)`. Its denominator needs `r`, which
/// neither render gives without bias: `b² + ε` (the relMSE of `a` against `b`, halved) divides by
/// whichever render was low, up to `r²/ε` times too much where a pixel is heavy-tailed (on the
/// textured scene at 2048 spp two pixels on the light's edge, values 0.28–2.4 from render to
/// render, carried 82–99% of it, one term 39), and the pair's mean `(a + b)/2` is large exactly
/// when a rare high sample made `(a − b)²` large, so such pixels count almost nothing (500× too
/// little in the unit test's rare-event pixels). With `c`
/// independent of the pair the expectation is `v·E[1/(c² + ε)]`: the relMSE weighed by `c`'s
/// denominators. Estimators compared with the same `c` weigh every pixel alike whatever its
/// noise in `c`, which is what a comparison needs.
pub fn pair_rel_mse(a: &[Vec3], b: &[Vec3], c: &[Vec3]) -> f64 {
    check_sizes(a, b);
    check_sizes(a, c);
    let mut rel = 0.0f64;
    for ((x, y), r) in a.iter().zip(b).zip(c) {
        for k in 0..3 {
            let (d, r) = ((x[k] - y[k]) as f64, r[k] as f64);
            rel += d * d / (2.0 * (r * r + REL_EPSILON));
        }
    }
    rel / (a.len() * 3) as f64
}

/// A named rectangle of pixels, `[x, x+w) × [y, y+h)` (rows top to bottom), over which
/// metrics are reported on their own: a scene's parts compared separately.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Region {
    /// Its name in tables.
    pub name: String,
    /// Left column.
    pub x: u32,
    /// Top row (rows from the top).
    pub y: u32,
    /// Width in pixels.
    pub w: u32,
    /// Height in pixels.
    pub h: u32,
}

impl Region {
    /// Parse `X,Y,W,H` or `NAME=X,Y,W,H` (an unnamed region is named by its numbers).
    pub fn parse(s: &str) -> Result<Region, String> {
        let s = s.trim();
        let (name, rect) = match s.split_once('=') {
            Some((n, r)) => (n.trim().to_string(), r),
            None => (s.to_string(), s),
        };
        let v: Vec<u32> = rect
            .split(',')
            .map(|x| x.trim().parse::<u32>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("region '{s}': expected X,Y,W,H (whole pixels)"))?;
        let [x, y, w, h] = v[..] else {
            return Err(format!("region '{s}': expected four numbers X,Y,W,H"));
        };
        if w == 0 || h == 0 || name.is_empty() || name.chars().any(char::is_whitespace) {
            return Err(format!(
                "region '{s}': needs a width and height of at least 1 and a name without spaces"
            ));
        }
        Ok(Region { name, x, y, w, h })
    }

    /// Parse a region list: one `NAME X,Y,W,H` per line; blank lines and `#` comments are
    /// skipped. Errors name the line.
    pub fn parse_list(text: &str) -> Result<Vec<Region>, String> {
        let mut out = Vec::new();
        for (no, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let (name, rect) = line
                .split_once(char::is_whitespace)
                .ok_or_else(|| format!("line {}: expected NAME X,Y,W,H", no + 1))?;
            let r = Region::parse(&format!("{name}={}", rect.trim()))
                .map_err(|e| format!("line {}: {e}", no + 1))?;
            out.push(r);
        }
        Ok(out)
    }

    /// An error unless the region lies inside a `width × height` image.
    pub fn check(&self, width: u32, height: u32) -> Result<(), String> {
        if self.x as u64 + self.w as u64 > width as u64
            || self.y as u64 + self.h as u64 > height as u64
        {
            return Err(format!(
                "region {} ({},{},{},{}) does not fit in the {width}×{height} image",
                self.name, self.x, self.y, self.w, self.h
            ));
        }
        Ok(())
    }

    /// The row-major indices of its pixels in an image `width` wide.
    pub fn indices(&self, width: u32) -> impl Iterator<Item = usize> + '_ {
        (self.y..self.y + self.h).flat_map(move |y| {
            (self.x..self.x + self.w).map(move |x| y as usize * width as usize + x as usize)
        })
    }
}

/// The metrics of `image` against `reference` (both `width` wide) over `region` only.
pub fn region_metrics(image: &[Vec3], reference: &[Vec3], width: u32, region: &Region) -> Metrics {
    let a: Vec<Vec3> = region.indices(width).map(|i| image[i]).collect();
    let b: Vec<Vec3> = region.indices(width).map(|i| reference[i]).collect();
    metrics(&a, &b)
}

/// Per-pixel relative squared error `(x − r)²/(r² + ε)`, averaged over channels: the error map.
pub fn relative_error_map(image: &[Vec3], reference: &[Vec3]) -> Vec<f64> {
    check_sizes(image, reference);
    image
        .iter()
        .zip(reference)
        .map(|(x, r)| {
            (0..3)
                .map(|c| {
                    let (x, r) = (x[c] as f64, r[c] as f64);
                    (x - r).powi(2) / (r * r + REL_EPSILON)
                })
                .sum::<f64>()
                / 3.0
        })
        .collect()
}

/// The per-pixel sample variance across runs (the variance of one run's estimate), averaged
/// over pixels and channels. Needs at least 2 runs.
pub fn variance_across_runs(runs: &[Vec<Vec3>]) -> f64 {
    assert!(runs.len() >= 2, "variance needs at least two runs");
    let k = runs.len() as f64;
    let n = runs[0].len();
    let mut total = 0.0;
    for i in 0..n {
        for c in 0..3 {
            let mean = runs.iter().map(|r| r[i][c] as f64).sum::<f64>() / k;
            let ss: f64 = runs.iter().map(|r| (r[i][c] as f64 - mean).powi(2)).sum();
            total += ss / (k - 1.0);
        }
    }
    total / (n * 3) as f64
}

/// The bias test over runs: `(t, p)` for the hypothesis that the runs' mean signed error is 0.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BiasTest {
    /// Student's t of the mean signed error.
    pub t: f64,
    /// Two-sided p-value with K − 1 degrees of freedom.
    pub p: f64,
}

/// Test whether K ≥ 2 runs are unbiased against `reference` (see the module doc).
pub fn bias_test(runs: &[Vec<Vec3>], reference: &[Vec3]) -> BiasTest {
    assert!(runs.len() >= 2, "the bias test needs at least two runs");
    let e: Vec<f64> = runs
        .iter()
        .map(|r| metrics(r, reference).mean_signed_error)
        .collect();
    let k = e.len() as f64;
    let mean = e.iter().sum::<f64>() / k;
    let sd = (e.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
    let t = if sd > 0.0 {
        mean / (sd / k.sqrt())
    } else if mean == 0.0 {
        0.0
    } else {
        f64::INFINITY.copysign(mean)
    };
    BiasTest {
        t,
        p: student_t_two_sided_p(t.abs(), k - 1.0),
    }
}

/// Per-pixel, per-channel bias z-scores `(m − r)/√(v_m + v_r)` (0 where both variances are 0
/// and the values agree to float rounding, ±∞ where they are 0 and the values differ).
pub fn bias_z_scores(
    mean: &[Vec3],
    mean_variance: &[Vec3],
    reference: &[Vec3],
    reference_variance: Option<&[Vec3]>,
) -> Vec<Vec3> {
    check_sizes(mean, reference);
    check_sizes(mean, mean_variance);
    (0..mean.len())
        .map(|i| {
            let vr = reference_variance.map_or(Vec3::ZERO, |v| v[i]);
            let v = mean_variance[i] + vr;
            let d = mean[i] - reference[i];
            Vec3::from_array(std::array::from_fn(|c| {
                if v[c] > 0.0 {
                    d[c] / v[c].sqrt()
                } else if d[c].abs() <= 1e-6 * mean[i][c].abs().max(reference[i][c].abs()) {
                    0.0 // no variance, equal up to float rounding
                } else {
                    f32::INFINITY.copysign(d[c])
                }
            }))
        })
        .collect()
}

/// The bias of a whole image against a reference, from the variances of both means.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ImageBias {
    /// `Σ(m − r) / √Σ(v_m + v_r)` over all pixels and channels: standard normal for an
    /// unbiased image whose pixel errors are independent (`None` without variance).
    pub z: Option<f64>,
    /// The largest per-pixel, per-channel `|z|` of [`bias_z_scores`].
    pub max_pixel_z: f64,
}

/// The image-level bias z and the largest per-pixel |z| of `mean` (with the variance of each
/// pixel's mean) against `reference` (with its own, if known).
pub fn image_bias(
    mean: &[Vec3],
    mean_variance: &[Vec3],
    reference: &[Vec3],
    reference_variance: Option<&[Vec3]>,
) -> ImageBias {
    let z = bias_z_scores(mean, mean_variance, reference, reference_variance);
    let (mut sum_d, mut sum_v, mut max_z) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..mean.len() {
        for c in 0..3 {
            sum_d += (mean[i][c] - reference[i][c]) as f64;
            sum_v += (mean_variance[i][c] + reference_variance.map_or(0.0, |rv| rv[i][c])) as f64;
            max_z = max_z.max((z[i][c] as f64).abs());
        }
    }
    ImageBias {
        z: (sum_v > 0.0).then(|| sum_d / sum_v.sqrt()),
        max_pixel_z: max_z,
    }
}

/// The mean of the per-pixel variances (over pixels and channels).
pub fn mean_variance(v: &[Vec3]) -> f64 {
    v.iter().map(|p| (p.x + p.y + p.z) as f64).sum::<f64>() / (3 * v.len().max(1)) as f64
}

/// The mean over pixels and channels of `v/(r² + 0.01)`: with `v` a reference's variance of its
/// mean and `r` its value, the floor its own noise puts under a relMSE measured against it
/// (`E[(x − r̃)²] = (x − r)² + v` for a reference `r̃` of mean `r` and variance `v`, to first
/// order in the denominator).
pub fn mean_relative_variance(v: &[Vec3], r: &[Vec3]) -> f64 {
    let sum: f64 = v
        .iter()
        .zip(r)
        .map(|(v, r)| {
            (0..3)
                .map(|c| v[c] as f64 / ((r[c] as f64).powi(2) + REL_EPSILON))
                .sum::<f64>()
        })
        .sum();
    sum / (3 * v.len().max(1)) as f64
}

/// A perceptually ordered colour map (a 5-stop approximation of viridis), `t ∈ [0, 1]`.
pub fn colormap(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        1.0
    } * 4.0;
    let i = (t as usize).min(3);
    let f = t - i as f64;
    std::array::from_fn(|c| (STOPS[i][c] + f * (STOPS[i + 1][c] - STOPS[i][c])).round() as u8)
}

/// False-colour an error map on a log scale over `[lo, hi]` (values ≤ lo are darkest).
pub fn false_colour(values: &[f64], lo: f64, hi: f64) -> Vec<[u8; 3]> {
    let (l0, l1) = (lo.max(1e-30).log10(), hi.max(lo * 10.0).log10());
    values
        .iter()
        .map(|&v| colormap((v.max(1e-30).log10() - l0) / (l1 - l0)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_of_known_images() {
        let r = vec![Vec3::splat(1.0), Vec3::new(0.0, 2.0, 4.0)];
        let x = vec![Vec3::splat(2.0), Vec3::new(0.0, 2.0, 1.0)];
        let m = metrics(&x, &r);
        // differences: 1,1,1, 0,0,-3 over 6 values
        assert!((m.mse - 12.0 / 6.0).abs() < 1e-12);
        assert!((m.rmse - 2f64.sqrt()).abs() < 1e-12);
        assert!((m.mae - 6.0 / 6.0).abs() < 1e-12);
        assert!((m.mean_signed_error - 0.0).abs() < 1e-12);
        let rel = (3.0 * 1.0 / 1.01 + 9.0 / (16.0 + 0.01)) / 6.0;
        assert!((m.rel_mse - rel).abs() < 1e-12);
        assert_eq!(metrics(&r, &r), Metrics::default());
        let map = relative_error_map(&x, &r);
        assert!((map[0] - 1.0 / 1.01).abs() < 1e-12);
        assert!((map[1] - 9.0 / 16.01 / 3.0).abs() < 1e-12);
    }

    /// The pair estimate against the relMSE its renders have by construction, `c` the true
    /// image, over 4·10⁴ pixels (1.2·10⁵ values). Light tails: every value `1 + σ·g`, g normal
    /// (Box–Muller on hashed uniforms), σ = 0.05: relMSE `σ²/1.01`; the terms are
    /// `σ²χ²₁/1.01`, relative sd √2 each, so the mean's relative sd is 0.41%: 4% is ten sd.
    /// Rare events: a value 0.1, or 10 with probability 1% (mean 0.199, variance 0.9703, relMSE
    /// `0.9703/(0.199² + 0.01)` = 19.56); a term is `(a − b)²/(2·0.0496)`, 0 when both are 0.1,
    /// about 988 when one of them is 10 (probability 1.98%), so its relative sd is
    /// `√(0.98/0.0198)` ≈ 7.0 and the mean's 2.0%: 20% is ten sd. There `b` as the reference
    /// (halved) reads `0.99·0.01·9.9²/(2·0.02)` = 24.3, 1.24× too high (`b² + ε` is 0.02 unless
    /// b is the rare 10; its terms' relative sd is `√(0.99/0.0099)` = 10, the mean's 2.9%, so
    /// the check above 1.1× has a margin of 3.9 sd), and the pair's mean as the denominator
    /// about 500× too low (`(a − b)²/(2(m² + ε))` ≈ 1.92 when the event happens: 0.038).
    #[test]
    fn pair_rel_mse_estimates_one_renders_relmse() {
        let n = 40_000;
        let u = |k: u64| (crate::math::mix64(k) >> 11) as f64 / (1u64 << 53) as f64;
        let normal = |k: u64| {
            let (u1, u2) = (u(2 * k).max(1e-300), u(2 * k + 1));
            (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
        };
        let render = |seed: u64, value: &dyn Fn(u64) -> f64| -> Vec<Vec3> {
            (0..n as u64)
                .map(|i| {
                    let k = |c: u64| value((seed << 40) + 3 * i + c) as f32;
                    Vec3::new(k(0), k(1), k(2))
                })
                .collect()
        };
        let sigma = 0.05;
        let light = |k: u64| 1.0 + sigma * normal(k);
        let (a, b) = (render(1, &light), render(2, &light));
        let want = sigma * sigma / (1.0 + REL_EPSILON);
        let got = pair_rel_mse(&a, &b, &vec![Vec3::ONE; n]);
        assert!(
            (got / want - 1.0).abs() < 0.04,
            "light tails: {got} against {want}"
        );
        let rare = |k: u64| if u(k) < 0.01 { 10.0 } else { 0.1 };
        let (a, b) = (render(3, &rare), render(4, &rare));
        let (mean, var) = (0.199f64, 0.01 * 100.0 + 0.99 * 0.01 - 0.199 * 0.199);
        let want = var / (mean * mean + REL_EPSILON);
        let got = pair_rel_mse(&a, &b, &vec![Vec3::splat(mean as f32); n]);
        assert!(
            (got / want - 1.0).abs() < 0.2,
            "rare events: {got} against {want}"
        );
        let against_b = metrics(&a, &b).rel_mse / 2.0;
        assert!(against_b > 1.1 * want, "b as the reference: {against_b}");
        let means: Vec<Vec3> = a.iter().zip(&b).map(|(x, y)| (*x + *y) / 2.0).collect();
        let own_mean = pair_rel_mse(&a, &b, &means);
        assert!(own_mean < want / 100.0, "the pair's mean as r: {own_mean}");
    }

    #[test]
    fn variance_and_bias_over_runs() {
        let r = vec![Vec3::ZERO; 2];
        let runs = vec![
            vec![Vec3::splat(1.0); 2],
            vec![Vec3::splat(-1.0); 2],
            vec![Vec3::splat(3.0); 2],
        ];
        // per value: mean 1, sample variance ((0)² + (−2)² + 2²)/2 = 4
        assert!((variance_across_runs(&runs) - 4.0).abs() < 1e-12);
        // e = 1, −1, 3: mean 1, sd 2, t = 1/(2/√3) = 0.866
        let b = bias_test(&runs, &r);
        assert!((b.t - 3f64.sqrt() / 2.0).abs() < 1e-12);
        assert!(b.p > 0.4 && b.p < 0.6);
        let biased = vec![
            vec![Vec3::splat(1.0); 2],
            vec![Vec3::splat(1.01); 2],
            vec![Vec3::splat(0.99); 2],
        ];
        assert!(bias_test(&biased, &r).p < 1e-3);
        let z = bias_z_scores(
            &[Vec3::splat(2.0)],
            &[Vec3::splat(3.0)],
            &[Vec3::ONE],
            Some(&[Vec3::ONE]),
        );
        assert!((z[0].x - 0.5).abs() < 1e-6);
        // two pixels off by +1 with variance 1 + 1 each: z = 6 / √12 per image
        let b = image_bias(
            &[Vec3::splat(2.0); 2],
            &[Vec3::ONE; 2],
            &[Vec3::ONE; 2],
            Some(&[Vec3::ONE; 2]),
        );
        assert!((b.z.unwrap() - 6.0 / 12f64.sqrt()).abs() < 1e-9);
        assert!((b.max_pixel_z - 0.5f64.sqrt()).abs() < 1e-6);
        assert!((mean_variance(&[Vec3::new(1.0, 2.0, 3.0)]) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn regions_parse_and_select_their_pixels() {
        let r = Region::parse("plate=1,2,3,4").unwrap();
        assert_eq!((r.name.as_str(), r.x, r.y, r.w, r.h), ("plate", 1, 2, 3, 4));
        assert_eq!(Region::parse("1,2,3,4").unwrap().name, "1,2,3,4");
        for bad in ["1,2,3", "1,2,0,4", "a,b,c,d", "x y=1,2,3,4", "1,2,3,4,5"] {
            assert!(Region::parse(bad).is_err(), "{bad}");
        }
        let list =
            Region::parse_list("# plates\nleft 0,0,1,2\n\nright 1,0,1,2 # comment\n").unwrap();
        assert_eq!(list.len(), 2);
        assert!(Region::parse_list("left 0,0,1\n")
            .unwrap_err()
            .starts_with("line 1"));
        assert!(list[1].check(2, 2).is_ok() && list[1].check(1, 2).is_err());
        assert_eq!(list[1].indices(2).collect::<Vec<_>>(), vec![1, 3]);
        let img = vec![Vec3::ZERO, Vec3::ONE, Vec3::ZERO, Vec3::ONE];
        let m = region_metrics(&img, &[Vec3::ZERO; 4], 2, &list[0]);
        assert_eq!(m.mse, 0.0);
        assert_eq!(region_metrics(&img, &[Vec3::ZERO; 4], 2, &list[1]).mse, 1.0);
    }

    #[test]
    fn colours() {
        assert_eq!(colormap(0.0), [68, 1, 84]);
        assert_eq!(colormap(1.0), [253, 231, 37]);
        let c = false_colour(&[1e-6, 1e-3, 1.0], 1e-6, 1.0);
        assert_eq!(c[0], colormap(0.0));
        assert_eq!(c[1], colormap(0.5));
        assert_eq!(c[2], colormap(1.0));
    }
}
