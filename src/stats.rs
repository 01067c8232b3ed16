//! Statistics for the tests and the analysis: the chi-square goodness-of-fit test of a
//! direction sampler against its pdf, the tail probabilities of the chi-square, normal and
//! Student-t distributions (from `statrs`), and Šidák's correction for many tests. Line fits
//! live in [`crate::analysis::fit`].
//!
//! The chi-square test bins directions on `(cosθ, φ)` about a chosen pole — equal-area bins,
//! since `dω = d(cosθ) dφ` — over `cosθ ∈ [z_lo, 1]`, plus one bin for `cosθ < z_lo` and one for
//! failed samples (`None`). Expected counts are `N ∫_bin pdf dω` by a K×K midpoint rule per bin;
//! the failed bin expects `N (1 − ∫ pdf dω)`. Bins expecting fewer than 5 samples are pooled
//! (smallest first) until the pool expects at least 5. The statistic `Σ (O−E)²/E` with
//! `bins − 1` degrees of freedom gives the p-value.

use crate::math::Frame;
use glam::{Vec2, Vec3};
use statrs::distribution::{ChiSquared, ContinuousCDF, Normal, StudentsT};
use std::f64::consts::PI;

/// Where and how finely to bin directions.
#[derive(Clone, Copy, Debug)]
pub struct Chi2Binning {
    /// The pole of the binning (unit).
    pub pole: Vec3,
    /// Bins cover `cosθ ∈ [z_lo, 1]` about the pole; lower `cosθ` share one bin.
    pub z_lo: f32,
    pub z_bins: usize,
    pub phi_bins: usize,
    /// Midpoint-rule points per bin side for the expected counts.
    pub quadrature: usize,
    /// What a regular bin that the quadrature found empty but that holds samples expects (0:
    /// nothing, so any sample there makes the statistic infinite). A pdf whose support ends at
    /// an outline inside a bin (a light seen from a point) can cover a sliver of it that the
    /// quadrature misses; with a small value (such bins are pooled) the test stays about the
    /// distribution, while many samples outside the support still raise the statistic.
    pub floor: f64,
}

impl Default for Chi2Binning {
    fn default() -> Self {
        Chi2Binning {
            pole: Vec3::Z,
            z_lo: -1.0,
            z_bins: 40,
            phi_bins: 80,
            quadrature: 6,
            floor: 0.0,
        }
    }
}

/// The outcome of a chi-square test.
#[derive(Clone, Copy, Debug)]
pub struct Chi2Result {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// `∫ pdf dω` over the sphere, by the same quadrature (1 for a normalized pdf).
    pub pdf_integral: f64,
    /// Samples that came back `None`.
    pub failed: usize,
}

/// Chi-square test of `sample(u)` (directions, `None` for a failed sample) against `pdf(ω)`
/// (per solid angle), with `n` points `u` from `points`.
pub fn chi2_directions(
    sample: impl FnMut(Vec2) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
    points: impl FnMut() -> Vec2,
    n: usize,
    b: &Chi2Binning,
) -> Chi2Result {
    chi2_directions_binned(sample, pdf, points, n, b).0
}

/// [`chi2_directions`], and its bins: the observed and the expected counts of the
/// `z_bins × phi_bins` regular bins, row-major by `cosθ` from `z_lo` up (`φ` along a row), for
/// pictures of a warp beside its integrated pdf.
pub fn chi2_directions_binned(
    mut sample: impl FnMut(Vec2) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
    mut points: impl FnMut() -> Vec2,
    n: usize,
    b: &Chi2Binning,
) -> (Chi2Result, Vec<f64>, Vec<f64>) {
    let bins = Bins::new(b);
    let (below, failed_bin) = (bins.below(), bins.below() + 1);
    let mut observed = bins.observed(&mut sample, &mut points, n);
    let mut expected = bins.expected_mass(pdf, b.quadrature.max(1));
    let total: f64 = expected[..failed_bin].iter().sum();
    expected[failed_bin] = (1.0 - total).max(0.0);
    for e in &mut expected {
        *e *= n as f64;
    }
    for (e, &o) in expected[..below].iter_mut().zip(&observed[..below]) {
        if *e == 0.0 && o > 0.0 {
            *e = b.floor;
        }
    }
    let (statistic, dof) = pooled_chi2(&observed, &expected);
    let result = Chi2Result {
        statistic,
        dof,
        p_value: chi2_sf(statistic, dof as f64),
        pdf_integral: total,
        failed: observed[failed_bin] as usize,
    };
    observed.truncate(below);
    expected.truncate(below);
    (result, observed, expected)
}

/// The bins of a [`Chi2Binning`] about its pole: `nz × np` regular ones, `dz` in `cosθ` from
/// `z_lo` by `dphi` in `φ`, then one for `cosθ < z_lo` ([`Bins::below`]) and one for failures.
struct Bins {
    frame: Frame,
    nz: usize,
    np: usize,
    z_lo: f64,
    dz: f64,
    dphi: f64,
}

impl Bins {
    fn new(b: &Chi2Binning) -> Bins {
        let z_lo = b.z_lo as f64;
        Bins {
            frame: Frame::from_normal(b.pole),
            nz: b.z_bins,
            np: b.phi_bins,
            z_lo,
            dz: (1.0 - z_lo) / b.z_bins as f64,
            dphi: 2.0 * PI / b.phi_bins as f64,
        }
    }

    /// The index of the bin of `cosθ < z_lo`; the failed samples' bin follows it.
    fn below(&self) -> usize {
        self.nz * self.np
    }

    /// The count in every bin of `n` directions `sample(points())`.
    fn observed(
        &self,
        mut sample: impl FnMut(Vec2) -> Option<Vec3>,
        mut points: impl FnMut() -> Vec2,
        n: usize,
    ) -> Vec<f64> {
        let (nz, np, z_lo) = (self.nz, self.np, self.z_lo);
        let below = self.below();
        let mut observed = vec![0f64; nz * np + 2];
        for _ in 0..n {
            match sample(points()) {
                None => observed[below + 1] += 1.0,
                Some(w) => {
                    let l = self.frame.to_local(w.normalize());
                    let z = l.z.clamp(-1.0, 1.0) as f64;
                    if z < z_lo {
                        observed[below] += 1.0;
                    } else {
                        let mut phi = (l.y as f64).atan2(l.x as f64);
                        if phi < 0.0 {
                            phi += 2.0 * PI;
                        }
                        let iz = (((z - z_lo) / self.dz) as usize).min(nz - 1);
                        let ip = ((phi / self.dphi) as usize).min(np - 1);
                        observed[iz * np + ip] += 1.0;
                    }
                }
            }
        }
        observed
    }

    /// `∫ pdf dω` over every bin but the failed one (left 0), by a `k×k` midpoint rule in
    /// `(z, φ)` per regular bin.
    fn expected_mass(&self, pdf: impl Fn(Vec3) -> f32, k: usize) -> Vec<f64> {
        let (nz, np, z_lo, dz, dphi) = (self.nz, self.np, self.z_lo, self.dz, self.dphi);
        let dir = |z: f64, phi: f64| {
            let r = (1.0 - z * z).max(0.0).sqrt();
            self.frame.to_world(Vec3::new(
                (r * phi.cos()) as f32,
                (r * phi.sin()) as f32,
                z as f32,
            ))
        };
        let integrate = |z0: f64, z1: f64, p0: f64, p1: f64, kz: usize, kp: usize| {
            let (hz, hp) = ((z1 - z0) / kz as f64, (p1 - p0) / kp as f64);
            let mut s = 0.0;
            for a in 0..kz {
                for c in 0..kp {
                    let z = z0 + (a as f64 + 0.5) * hz;
                    let phi = p0 + (c as f64 + 0.5) * hp;
                    s += pdf(dir(z, phi)) as f64;
                }
            }
            s * hz * hp
        };
        let mut expected = vec![0f64; nz * np + 2];
        for iz in 0..nz {
            for ip in 0..np {
                let z0 = z_lo + iz as f64 * dz;
                let p0 = ip as f64 * dphi;
                expected[iz * np + ip] = integrate(z0, z0 + dz, p0, p0 + dphi, k, k);
            }
        }
        // Below z_lo: intervals that double in width away from z_lo, so a pdf that is still
        // steep just below z_lo (a sharp lobe) is integrated as finely as the bins above it.
        let (mut hi, mut width) = (z_lo, dz);
        while hi > -1.0 {
            let lo = (hi - width).max(-1.0);
            expected[self.below()] += integrate(lo, hi, 0.0, 2.0 * PI, k, np * k);
            hi = lo;
            width *= 2.0;
        }
        expected
    }
}

/// Pearson's statistic over bins, pooling bins expecting < 5 (smallest first); a bin that
/// expects nothing but observes something makes the statistic infinite.
pub fn pooled_chi2(observed: &[f64], expected: &[f64]) -> (f64, usize) {
    let mut idx: Vec<usize> = (0..observed.len()).collect();
    idx.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut stat, mut bins) = (0.0, 0usize);
    let (mut po, mut pe) = (0.0, 0.0);
    for &i in &idx {
        let (o, e) = (observed[i], expected[i]);
        if e <= 0.0 {
            if o > 0.0 {
                return (f64::INFINITY, 1);
            }
            continue;
        }
        if e < 5.0 || pe > 0.0 && pe < 5.0 {
            po += o;
            pe += e;
            if pe >= 5.0 {
                stat += (po - pe).powi(2) / pe;
                bins += 1;
                po = 0.0;
                pe = 0.0;
            }
            continue;
        }
        stat += (o - e).powi(2) / e;
        bins += 1;
    }
    if pe > 0.0 {
        stat += (po - pe).powi(2) / pe;
        bins += 1;
    }
    (stat, bins.saturating_sub(1).max(1))
}

/// Two-sided tail of Student's t with `dof > 0` degrees of freedom: `P(|T| > t)`.
pub fn student_t_two_sided_p(t: f64, dof: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    let d = StudentsT::new(0.0, 1.0, dof).expect("positive degrees of freedom");
    (2.0 * d.sf(t.abs())).min(1.0)
}

/// Survival function of the chi-square distribution: `P(X > x)` with `k > 0` degrees of
/// freedom.
pub fn chi2_sf(x: f64, k: f64) -> f64 {
    if x.is_infinite() {
        return 0.0;
    }
    ChiSquared::new(k)
        .expect("positive degrees of freedom")
        .sf(x)
}

/// Two-sided tail of the standard normal: `P(|Z| > z)`.
pub fn normal_two_sided_p(z: f64) -> f64 {
    2.0 * Normal::standard().sf(z.abs())
}

/// Per-test significance for `m` tests at family-wise significance `alpha` (Šidák).
pub fn sidak(alpha: f64, m: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / m.max(1) as f64)
}

/// `|z|` beyond which a two-sided test at significance `alpha` rejects: `Φ⁻¹(1 − α/2)`.
pub fn normal_critical_value(alpha: f64) -> f64 {
    Normal::standard().inverse_cdf(1.0 - 0.5 * alpha)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tails_match_known_values() {
        // chi-square with 1 dof: P(X > 3.841459) = 0.05; with 10 dof: P(X > 23.209) = 0.01
        assert!((chi2_sf(3.841_459, 1.0) - 0.05).abs() < 1e-6);
        assert!((chi2_sf(23.209_25, 10.0) - 0.01).abs() < 1e-6);
        assert!((normal_two_sided_p(1.959_964) - 0.05).abs() < 1e-6);
        assert!((normal_critical_value(0.05) - 1.959_964).abs() < 1e-5);
        assert!((sidak(0.01, 1) - 0.01).abs() < 1e-15);
        // Student t: P(|T| > 2.228) = 0.05 with 10 dof; P(|T| > 12.706) = 0.05 with 1 dof
        assert!((student_t_two_sided_p(2.228_139, 10.0) - 0.05).abs() < 1e-6);
        assert!((student_t_two_sided_p(12.706_2, 1.0) - 0.05).abs() < 1e-5);
        assert!((student_t_two_sided_p(0.0, 5.0) - 1.0).abs() < 1e-12);
    }
}
