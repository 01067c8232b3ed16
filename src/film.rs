//! The film: per-pixel running sums in f64, so the mean, the sample variance and the variance of
//! the mean are known for every pixel, and films of the same scene and settings merge exactly.
//!
//! For `n` samples `x_i` of a pixel: mean `m = Σx/n`, sample variance
//! `s² = (Σx² − n m²)/(n − 1)`, variance of the mean `s²/n` (exact for independent samples; for
//! stratified samples it is an upper bound, since strata remove variance between samples).

use glam::{DVec3, Vec3};

/// Per-pixel sums of samples and of their squares, and sample counts.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    sum: Vec<DVec3>,
    sum_sq: Vec<DVec3>,
    count: Vec<u64>,
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Film {
        let n = width as usize * height as usize;
        Film {
            width,
            height,
            sum: vec![DVec3::ZERO; n],
            sum_sq: vec![DVec3::ZERO; n],
            count: vec![0; n],
        }
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.count.len()
    }

    /// True for a 0×0 film.
    pub fn is_empty(&self) -> bool {
        self.count.is_empty()
    }

    /// Linear index of pixel (x, y), rows top to bottom.
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// Add the sums of one pixel (from a tile rendered elsewhere).
    #[inline]
    pub fn add_pixel_sums(&mut self, i: usize, sum: DVec3, sum_sq: DVec3, count: u64) {
        self.sum[i] += sum;
        self.sum_sq[i] += sum_sq;
        self.count[i] += count;
    }

    /// The sums and count of pixel `i`.
    #[inline]
    pub fn pixel_sums(&self, i: usize) -> (DVec3, DVec3, u64) {
        (self.sum[i], self.sum_sq[i], self.count[i])
    }

    /// Replace the sums and count of pixel `i` (a render that went on from them).
    #[inline]
    pub fn set_pixel_sums(&mut self, i: usize, sum: DVec3, sum_sq: DVec3, count: u64) {
        self.sum[i] = sum;
        self.sum_sq[i] = sum_sq;
        self.count[i] = count;
    }

    /// Add one sample to pixel `i`.
    #[cfg(test)]
    fn add_sample(&mut self, i: usize, v: Vec3) {
        let v = v.as_dvec3();
        self.add_pixel_sums(i, v, v * v, 1);
    }

    /// Samples in pixel `i`.
    pub fn count(&self, i: usize) -> u64 {
        self.count[i]
    }

    /// Mean of pixel `i` (zero with no samples).
    pub fn mean(&self, i: usize) -> DVec3 {
        match self.count[i] {
            0 => DVec3::ZERO,
            n => self.sum[i] / n as f64,
        }
    }

    /// Unbiased sample variance of pixel `i`'s samples (zero with fewer than 2).
    pub fn sample_variance(&self, i: usize) -> DVec3 {
        let n = self.count[i];
        if n < 2 {
            return DVec3::ZERO;
        }
        let m = self.sum[i] / n as f64;
        ((self.sum_sq[i] - m * self.sum[i]) / (n - 1) as f64).max(DVec3::ZERO)
    }

    /// Variance of pixel `i`'s mean, `s²/n`.
    pub fn variance_of_mean(&self, i: usize) -> DVec3 {
        match self.count[i] {
            0 => DVec3::ZERO,
            n => self.sample_variance(i) / n as f64,
        }
    }

    /// Kish's effective sample size of pixel `i` per channel, `(Σx)²/Σx²`: about the number of
    /// samples that carry the pixel's value (for a value that is `c` with probability `p` and 0
    /// otherwise it is `n·p`). Small values mean a mean made of a few rare samples, whose
    /// distribution is far from normal.
    pub fn effective_samples(&self, i: usize) -> DVec3 {
        let s2 = self.sum_sq[i];
        DVec3::select(
            s2.cmpgt(DVec3::ZERO),
            self.sum[i] * self.sum[i] / s2,
            DVec3::ZERO,
        )
    }

    /// The number of samples in each pixel's mean, row-major (saturating at `u32::MAX`).
    pub fn sample_counts(&self) -> Vec<u32> {
        self.count
            .iter()
            .map(|&n| n.min(u32::MAX as u64) as u32)
            .collect()
    }

    /// The mean image, row-major, as f32.
    pub fn mean_image(&self) -> Vec<Vec3> {
        (0..self.len()).map(|i| self.mean(i).as_vec3()).collect()
    }

    /// The variance-of-the-mean image, row-major, as f32.
    pub fn variance_image(&self) -> Vec<Vec3> {
        (0..self.len())
            .map(|i| self.variance_of_mean(i).as_vec3())
            .collect()
    }

    /// Add `other`'s samples to this film. Exact: sums add. Films of different sizes do not
    /// merge: the error says both sizes.
    pub fn merge(&mut self, other: &Film) -> Result<(), String> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(format!(
                "cannot merge a {}×{} film into a {}×{} one",
                other.width, other.height, self.width, self.height
            ));
        }
        for i in 0..self.len() {
            self.add_pixel_sums(i, other.sum[i], other.sum_sq[i], other.count[i]);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_variance_match_direct_formulas() {
        let mut f = Film::new(1, 1);
        let xs = [1.0f32, 2.0, 4.0, 7.0];
        for x in xs {
            f.add_sample(0, Vec3::splat(x));
        }
        let m = 3.5;
        let s2 = xs.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>() / 3.0;
        assert!((f.mean(0).x - m).abs() < 1e-12);
        assert!((f.sample_variance(0).x - s2).abs() < 1e-12);
        assert!((f.variance_of_mean(0).x - s2 / 4.0).abs() < 1e-12);
        // (1+2+4+7)² / (1+4+16+49)
        assert!((f.effective_samples(0).x - 196.0 / 70.0).abs() < 1e-12);
        let mut g = Film::new(1, 1);
        for k in 0..100 {
            g.add_sample(0, Vec3::splat(if k % 10 == 0 { 5.0 } else { 0.0 }));
        }
        assert!((g.effective_samples(0).x - 10.0).abs() < 1e-12);
    }

    #[test]
    fn merge_equals_one_film() {
        let mut a = Film::new(2, 1);
        let mut b = Film::new(2, 1);
        let mut all = Film::new(2, 1);
        for k in 0..10 {
            let v = Vec3::new(k as f32, 1.0, 0.5 * k as f32);
            if k % 3 == 0 {
                a.add_sample(1, v)
            } else {
                b.add_sample(1, v)
            }
            all.add_sample(1, v);
        }
        a.merge(&b).unwrap();
        assert_eq!(a.count(1), 10);
        assert!((a.mean(1) - all.mean(1)).length() < 1e-12);
        assert!((a.sample_variance(1) - all.sample_variance(1)).length() < 1e-12);
        assert!(a.merge(&Film::new(1, 1)).is_err());
    }
}
