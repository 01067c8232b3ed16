//! The environment: the radiance that rays escaping the scene bring from infinitely far away,
//! either one constant colour or an HDR lat-long map, and how a map is importance-sampled.
//!
//! **The lat-long convention** (`[environment] map = "sky.exr"`), +y up. The direction
//! `d = (sinθ sinφ, cosθ, −sinθ cosφ)`, with θ ∈ [0, π] measured from +y (the zenith) and
//! φ ∈ [−π, π) about y (φ = 0 toward −z, φ = π/2 toward +x), is the point `(u, v) =
//! (φ/2π + ½, θ/π)` of the map: column `⌊u·W⌋`, row `⌊v·H⌋` of a W × H image whose row 0 is at
//! the top. So the middle of the map lies toward −z (where a camera looks by default), its
//! left quarter line toward −x, its right quarter line toward +x, its left and right edges
//! toward +z; the top row is the zenith, the bottom row the nadir:
//!
//! ```text
//!   u = 0      ¼        ½        ¾        1
//!   +---------+--------+--------+--------+   v = 0: zenith (+y)
//!   |   +z    |   −x   |   −z   |   +x   |   v = ½: horizon
//!   +---------+--------+--------+--------+   v = 1: nadir (−y)
//! ```
//!
//! `rotation` (degrees) turns the map about +y, counter-clockwise seen from above (a world
//! direction is turned by −rotation before it is looked up: with 90°, what lay toward −z lies
//! toward −x); `scale` multiplies its radiance. The radiance of a direction is its texel's
//! (nearest: piecewise constant over the map, like its sampling density).
//!
//! **Importance sampling** (pbrt-v4's `ImageInfiniteLight`, Mitsuba's `envmap`): a piecewise
//! constant density on [0, 1]² proportional to `f(x, y) = lum(L_xy)·sin θ_y` (θ at the row's
//! centre): a row from the marginal of the rows' sums, then a column from the row's conditional,
//! each continuous inside its texel. Its density at `(u, v)` is `p(u, v) = f(x, y)/f̄` (f̄ the
//! mean of f), and per solid angle `p_ω = p(u, v)/(2π² sin θ)`, since `dω = 2π² sin θ du dv`.
//! Texels of zero luminance are never sampled; they hold no radiance (RGB is non-negative), so
//! no estimator misses any. The light's power for the light choice is `πR²·∫lum(L) dω` (the
//! environment seen by a scene of bounding radius R, as for the constant one, `4π·πR²·lum`),
//! with `∫lum(L) dω = Σ lum(L_xy)·ΔΩ_y` over texels of exact solid angle
//! `ΔΩ_y = (2π/W)(cos θ_y0 − cos θ_y1)`.

use crate::math::luminance;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// What rays that escape the scene see.
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// The same radiance in every direction (black: no environment light).
    Constant(Vec3),
    /// An HDR lat-long map.
    Map(EnvMap),
}

impl From<Vec3> for Environment {
    fn from(c: Vec3) -> Environment {
        Environment::Constant(c)
    }
}

impl Default for Environment {
    fn default() -> Environment {
        Environment::Constant(Vec3::ZERO)
    }
}

/// Size of the [`Environment::studio`] map (lat-long, texels).
const STUDIO_SIZE: (u32, u32) = (128, 64);
/// The studio's ambient radiance, the same from every direction.
const STUDIO_AMBIENT: f32 = 0.5;
/// Angular radius of the studio's key light (radians: 8°).
const STUDIO_KEY_RADIUS: f32 = 0.14;
/// What the key light adds to a white diffuse surface facing it: `ρ·E/π` with ρ = 1, so
/// `E = π·STUDIO_KEY_GAIN` (a surface facing it reads 0.5 + 0.6, one facing away 0.5).
const STUDIO_KEY_GAIN: f32 = 0.6;

impl Environment {
    /// The light of a scene that brings none of its own (no emitters, or emitters that light
    /// nothing the camera sees): an even grey sky of radiance 0.5 and one soft key light, a
    /// disc of 8° radius toward `key` (unit, world space) whose irradiance at normal incidence
    /// is `0.6π`. Under a uniform sky alone a white object is lit exactly as bright as the sky
    /// behind it and vanishes (the white furnace); the key light shades its faces by their
    /// angle to it and casts shadows, so its shape shows. A lat-long map, importance-sampled as
    /// any `[environment] map`: the disc's texels carry its radiance `0.6π/Ω` (Ω the disc's
    /// exact solid angle on the map's texels), so it is found by light samples, not by chance.
    pub fn studio(key: Vec3) -> Environment {
        let (w, h) = STUDIO_SIZE;
        let key = key.normalize_or(Vec3::Y);
        let cos_r = STUDIO_KEY_RADIUS.cos();
        // texel centres in the map's convention (module doc), and each row's solid angle
        let dir = |x: u32, y: u32| {
            let (phi, theta) = (
                2.0 * PI * ((x as f32 + 0.5) / w as f32 - 0.5),
                PI * (y as f32 + 0.5) / h as f32,
            );
            let (st, ct) = theta.sin_cos();
            let (sp, cp) = phi.sin_cos();
            Vec3::new(st * sp, ct, -st * cp)
        };
        let texel_sr = |y: u32| {
            let (t0, t1) = (PI * y as f32 / h as f32, PI * (y + 1) as f32 / h as f32);
            (2.0 * PI / w as f32) * (t0.cos() - t1.cos())
        };
        let in_key = |x: u32, y: u32| dir(x, y).dot(key) >= cos_r;
        let omega: f32 = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| in_key(x, y))
            .map(|(_, y)| texel_sr(y))
            .sum();
        let l_key = if omega > 0.0 {
            PI * STUDIO_KEY_GAIN / omega
        } else {
            0.0
        };
        let pixels: Vec<Vec3> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| Vec3::splat(STUDIO_AMBIENT + if in_key(x, y) { l_key } else { 0.0 }))
            .collect();
        let map = EnvMap::new(w, h, &pixels, 0.0, 1.0).expect("the studio map is well formed");
        Environment::Map(map)
    }

    /// The radiance arriving along `-d` from direction `d` (unit, world space).
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        match self {
            Environment::Constant(c) => *c,
            Environment::Map(m) => m.radiance(d),
        }
    }

    /// `∫ lum(L(ω)) dω` over the sphere.
    pub fn luminance_integral(&self) -> f64 {
        match self {
            Environment::Constant(c) => 4.0 * std::f64::consts::PI * luminance(*c).max(0.0) as f64,
            Environment::Map(m) => m.luminance_integral,
        }
    }

    /// The map, if it is one.
    pub fn map(&self) -> Option<&EnvMap> {
        match self {
            Environment::Map(m) => Some(m),
            Environment::Constant(_) => None,
        }
    }

    /// Words for the hash of a scene: the constant, or the map's size, texels and rotation.
    pub fn hash_words(&self) -> Vec<u64> {
        let bits = |v: Vec3| v.to_array().map(|x| x.to_bits() as u64);
        match self {
            Environment::Constant(c) => bits(*c).to_vec(),
            Environment::Map(m) => {
                let mut w = vec![m.width as u64, m.height as u64, m.rotation.to_bits() as u64];
                w.extend(m.texels.iter().flat_map(|&t| bits(t)));
                w
            }
        }
    }
}

/// A 1D piecewise-constant density on [0, 1) over `n` equal cells (pbrt's
/// `PiecewiseConstant1D`).
#[derive(Clone, Debug, PartialEq)]
struct Piecewise {
    /// The cells' values (non-negative).
    func: Vec<f32>,
    /// `cdf[i]`: the share of the cells before `i`; `cdf[n] = 1`.
    cdf: Vec<f32>,
    /// The mean of `func`: the density of cell `i` is `func[i]/mean`.
    mean: f32,
}

impl Piecewise {
    fn new(func: Vec<f32>) -> Piecewise {
        let n = func.len();
        let total: f64 = func.iter().map(|&f| f as f64).sum();
        let mut cdf = Vec::with_capacity(n + 1);
        let mut run = 0.0f64;
        cdf.push(0.0);
        for &f in &func {
            run += f as f64;
            cdf.push(if total > 0.0 {
                (run / total) as f32
            } else {
                0.0
            });
        }
        if total > 0.0 {
            cdf[n] = 1.0;
        }
        Piecewise {
            mean: (total / n as f64) as f32,
            func,
            cdf,
        }
    }

    /// The point for `u ∈ [0, 1)`, its cell and its density. The cell found has `cdf[i] ≤ u <
    /// cdf[i + 1]`, so it has positive value.
    #[inline]
    fn sample(&self, u: f32) -> (f32, usize, f32) {
        let n = self.func.len();
        let i = self.cdf.partition_point(|&c| c <= u).clamp(1, n) - 1;
        let (c0, c1) = (self.cdf[i], self.cdf[i + 1]);
        let du = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.5 };
        let x = ((i as f32 + du.clamp(0.0, 1.0)) / n as f32).min(1.0 - f32::EPSILON);
        (x, i, self.density(i))
    }

    #[inline]
    fn density(&self, i: usize) -> f32 {
        if self.mean > 0.0 {
            self.func[i] / self.mean
        } else {
            0.0
        }
    }
}

/// An HDR lat-long environment map (see the module doc for its convention) with its sampling
/// distribution.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    width: u32,
    height: u32,
    /// Radiance (scale applied), row-major, row 0 at the zenith.
    texels: Vec<Vec3>,
    /// Rotation about +y, radians, and its cosine and sine.
    rotation: f32,
    cos_sin: (f32, f32),
    /// Per row, the conditional density over its columns.
    rows: Vec<Piecewise>,
    /// The density over rows.
    marginal: Piecewise,
    /// `∫ lum(L) dω`.
    luminance_integral: f64,
}

impl EnvMap {
    /// A `width × height` map of linear RGB `pixels` (row-major, row 0 at the top), turned by
    /// `rotation_deg` about +y and scaled by `scale`. Err when the sizes disagree, or a pixel is
    /// negative or not finite (naming the first such pixel).
    pub fn new(
        width: u32,
        height: u32,
        pixels: &[Vec3],
        rotation_deg: f32,
        scale: f32,
    ) -> Result<EnvMap, String> {
        let (w, h) = (width as usize, height as usize);
        if w == 0 || h == 0 || pixels.len() != w * h {
            return Err(format!(
                "a {width}×{height} map needs {} pixels, not {}",
                w * h,
                pixels.len()
            ));
        }
        if let Some(k) = pixels
            .iter()
            .position(|p| !p.is_finite() || p.min_element() < 0.0)
        {
            return Err(format!(
                "pixel ({}, {}) is {} : radiance must be finite and non-negative",
                k % w,
                k / w,
                pixels[k]
            ));
        }
        if !(scale.is_finite() && scale >= 0.0 && rotation_deg.is_finite()) {
            return Err(format!(
                "scale {scale} and rotation {rotation_deg} must be finite, the scale ≥ 0"
            ));
        }
        let texels: Vec<Vec3> = pixels.iter().map(|&p| p * scale).collect();
        // the scale may carry a texel past what sums of squared radiance keep finite
        let max = crate::limits::MAX_MAGNITUDE;
        if let Some(k) = texels
            .iter()
            .position(|t| !t.is_finite() || t.max_element() > max)
        {
            return Err(format!(
                "pixel ({}, {}) is {} : times the scale {scale} it is {}, above the largest \
                 radiance vrpt takes ({max:e})",
                k % w,
                k / w,
                pixels[k],
                texels[k]
            ));
        }
        let mut rows = Vec::with_capacity(h);
        let mut luminance_integral = 0.0f64;
        for y in 0..h {
            let theta = PI * (y as f32 + 0.5) / h as f32;
            let row = &texels[y * w..(y + 1) * w];
            let lum: Vec<f32> = row.iter().map(|&t| luminance(t).max(0.0)).collect();
            let (t0, t1) = (
                std::f64::consts::PI * y as f64 / h as f64,
                std::f64::consts::PI * (y + 1) as f64 / h as f64,
            );
            let solid_angle = 2.0 * std::f64::consts::PI / w as f64 * (t0.cos() - t1.cos());
            luminance_integral += lum.iter().map(|&l| l as f64).sum::<f64>() * solid_angle;
            rows.push(Piecewise::new(
                lum.iter().map(|&l| l * theta.sin()).collect(),
            ));
        }
        let marginal = Piecewise::new(rows.iter().map(|r| r.mean).collect());
        let rotation = rotation_deg.to_radians();
        Ok(EnvMap {
            width,
            height,
            texels,
            rotation,
            cos_sin: (rotation.cos(), rotation.sin()),
            rows,
            marginal,
            luminance_integral,
        })
    }

    /// The map's size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// A world direction in the map's frame (turned by −rotation about y).
    #[inline]
    fn to_map(&self, d: Vec3) -> Vec3 {
        let (c, s) = self.cos_sin;
        Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    /// A map-frame direction in the world (turned by +rotation about y).
    #[inline]
    fn to_world(&self, d: Vec3) -> Vec3 {
        let (c, s) = self.cos_sin;
        Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// The map point `(u, v)` of the world direction `d` (unit).
    #[inline]
    pub fn uv(&self, d: Vec3) -> Vec2 {
        let m = self.to_map(d);
        let theta = m.y.clamp(-1.0, 1.0).acos();
        let phi = m.x.atan2(-m.z);
        Vec2::new(phi / (2.0 * PI) + 0.5, theta / PI)
    }

    /// The world direction of the map point `(u, v)`.
    #[inline]
    pub fn direction(&self, uv: Vec2) -> Vec3 {
        let (phi, theta) = (2.0 * PI * (uv.x - 0.5), PI * uv.y);
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        self.to_world(Vec3::new(st * sp, ct, -st * cp))
    }

    /// The texel (column, row) holding the map point `uv`.
    #[inline]
    fn texel(&self, uv: Vec2) -> (usize, usize) {
        let x = ((uv.x * self.width as f32) as usize).min(self.width as usize - 1);
        let y = ((uv.y * self.height as f32) as usize).min(self.height as usize - 1);
        (x, y)
    }

    /// The radiance from direction `d` (unit, world space).
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        let (x, y) = self.texel(self.uv(d));
        self.texels[y * self.width as usize + x]
    }

    /// A direction drawn in proportion to luminance × sinθ from `u`: (direction, its radiance,
    /// its pdf per solid angle). `None` for a black map or a draw on a pole.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        if self.marginal.mean <= 0.0 {
            return None;
        }
        let (v, y, pv) = self.marginal.sample(u.y);
        let (uu, x, pu) = self.rows[y].sample(u.x);
        let sin_theta = (PI * v).sin();
        let pdf = pv * pu / (2.0 * PI * PI * sin_theta);
        if !(sin_theta > 0.0 && pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let le = self.texels[y * self.width as usize + x];
        Some((self.direction(Vec2::new(uu, v)), le, pdf))
    }

    /// The pdf per solid angle with which [`EnvMap::sample`] returns direction `d`.
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        let uv = self.uv(d);
        let (x, y) = self.texel(uv);
        let sin_theta = (PI * uv.y).sin();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        self.marginal.density(y) * self.rows[y].density(x) / (2.0 * PI * PI * sin_theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The convention of the module doc, point by point.
    #[test]
    fn the_lat_long_convention() {
        let m = EnvMap::new(4, 2, &[Vec3::ONE; 8], 0.0, 1.0).unwrap();
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        let horizon = |u: f32| m.direction(Vec2::new(u, 0.5));
        assert!(close(horizon(0.5), -Vec3::Z));
        assert!(close(horizon(0.25), -Vec3::X));
        assert!(close(horizon(0.75), Vec3::X));
        assert!(close(horizon(0.0), Vec3::Z));
        assert!(close(m.direction(Vec2::new(0.3, 0.0)), Vec3::Y));
        assert!(close(m.direction(Vec2::new(0.3, 1.0)), -Vec3::Y));
        for uv in [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.6, 0.7),
            Vec2::new(0.9, 0.45),
        ] {
            assert!((m.uv(m.direction(uv)) - uv).length() < 1e-5, "{uv}");
        }
        // 90°: what lay toward −z lies toward −x
        let r = EnvMap::new(4, 2, &[Vec3::ONE; 8], 90.0, 1.0).unwrap();
        assert!(close(r.direction(Vec2::new(0.5, 0.5)), -Vec3::X));
        assert!((r.uv(-Vec3::X) - Vec2::new(0.5, 0.5)).length() < 1e-5);
    }

    /// Texel lookup: the texel a direction falls in, at the corners of the map and across the
    /// wrap at u = 0/1, with the scale applied.
    #[test]
    fn radiance_is_the_texel_of_the_direction() {
        let px: Vec<Vec3> = (0..8).map(|k| Vec3::splat(k as f32)).collect();
        let m = EnvMap::new(4, 2, &px, 0.0, 2.0).unwrap();
        let at = |u: f32, v: f32| m.radiance(m.direction(Vec2::new(u, v))).x;
        assert_eq!(at(0.01, 0.01), 0.0);
        assert_eq!(at(0.99, 0.01), 6.0);
        assert_eq!(at(0.6, 0.9), 2.0 * 6.0);
        assert_eq!(at(0.26, 0.6), 2.0 * 5.0);
        // just either side of +z (u = 0 ≡ 1)
        let eps = 1e-3;
        assert_eq!(
            m.radiance(Vec3::new(eps, 0.1, 1.0).normalize()).x,
            2.0 * 3.0
        );
        assert_eq!(m.radiance(Vec3::new(-eps, 0.1, 1.0).normalize()).x, 0.0);
    }

    /// Negative, NaN and mis-sized pixels are refused, naming the pixel.
    #[test]
    fn bad_maps_are_refused() {
        let mut px = vec![Vec3::ONE; 8];
        px[5] = Vec3::new(1.0, -1.0, 0.0);
        let e = EnvMap::new(4, 2, &px, 0.0, 1.0).unwrap_err();
        assert!(e.contains("pixel (1, 1)"), "{e}");
        px[5] = Vec3::NAN;
        assert!(EnvMap::new(4, 2, &px, 0.0, 1.0).is_err());
        assert!(EnvMap::new(4, 3, &[Vec3::ONE; 8], 0.0, 1.0).is_err());
        assert!(EnvMap::new(4, 2, &[Vec3::ONE; 8], 0.0, f32::NAN).is_err());
    }

    /// A constant map integrates to 4π·lum, and a sample's pdf is the pdf of its direction.
    #[test]
    fn integral_and_sample_pdf_agree() {
        let m = EnvMap::new(16, 8, &[Vec3::splat(2.0); 128], 30.0, 1.0).unwrap();
        assert!((m.luminance_integral - 8.0 * std::f64::consts::PI).abs() < 1e-4);
        let px: Vec<Vec3> = (0..128).map(|k| Vec3::splat((k % 7) as f32)).collect();
        let m = EnvMap::new(16, 8, &px, 30.0, 1.0).unwrap();
        for k in 0..200 {
            let u = Vec2::new((k as f32 * 0.618_034) % 1.0, (k as f32 * 0.754_878) % 1.0);
            let Some((d, le, pdf)) = m.sample(u) else {
                continue;
            };
            assert!(le.x > 0.0, "a black texel was sampled");
            assert!(
                (m.pdf(d) - pdf).abs() <= 1e-3 * pdf,
                "{u}: {} vs {pdf}",
                m.pdf(d)
            );
            assert_eq!(m.radiance(d), le);
        }
    }
}
