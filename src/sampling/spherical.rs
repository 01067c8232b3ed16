//! Directions uniform in the solid angle a triangle ([`SphericalTriangle`], Arvo 1995) or a
//! rectangle ([`SphericalRectangle`], Ureña, Fajardo & King 2013) subtends from a point, each
//! with its exact inverse; in f64 (see the [module above](super)).

use super::*;
use glam::DVec3;

/// The angle between unit vectors, accurate for nearly parallel and nearly opposite ones.
#[inline]
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    if a.dot(b) < 0.0 {
        std::f64::consts::PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).min(1.0).asin()
    }
}

/// `v` without its component along the unit `w`.
#[inline]
fn gram_schmidt(v: DVec3, w: DVec3) -> DVec3 {
    v - v.dot(w) * w
}

/// The spherical triangle that a triangle `v` subtends from a point `p`: its vertex directions,
/// the angle at `a` and its area (= its solid angle, `α + β + γ − π`). Sampling is Arvo's: `u₀`
/// picks the area of the sub-triangle `(a, b, c′)` with `c′` on the arc `ac`, `u₁` the point on
/// the arc `b c′` so the density is uniform; `u = (·, 0)` maps to `b`, `(0, 1)` to `a`, `(1, 1)`
/// to `c` (the corners of a [`sample_bilinear`] warp: weights `[b, b, a, c]`).
#[derive(Clone, Copy, Debug)]
pub struct SphericalTriangle {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    alpha: f64,
    area: f64,
}

impl SphericalTriangle {
    /// `None` when `p` lies on the triangle's plane or a vertex: no solid angle to sample.
    pub fn new(v: [Vec3; 3], p: Vec3) -> Option<SphericalTriangle> {
        let p = p.as_dvec3();
        let a = (v[0].as_dvec3() - p).try_normalize()?;
        let b = (v[1].as_dvec3() - p).try_normalize()?;
        let c = (v[2].as_dvec3() - p).try_normalize()?;
        let n_ab = a.cross(b).try_normalize()?;
        let n_bc = b.cross(c).try_normalize()?;
        let n_ca = c.cross(a).try_normalize()?;
        let alpha = angle_between(n_ab, -n_ca);
        let beta = angle_between(n_bc, -n_ab);
        let gamma = angle_between(n_ca, -n_bc);
        let area = alpha + beta + gamma - std::f64::consts::PI;
        (area > 0.0).then_some(SphericalTriangle {
            a,
            b,
            c,
            alpha,
            area,
        })
    }

    /// Its solid angle.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The vertex directions `[a, b, c]` (unit).
    pub fn vertices(&self) -> [DVec3; 3] {
        [self.a, self.b, self.c]
    }

    /// A direction uniform in the spherical triangle (unit, world space).
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let (a, b, c) = (self.a, self.b, self.c);
        let (u0, u1) = (u.x as f64, u.y as f64);
        let pi = std::f64::consts::PI;
        // the sub-triangle (a, b, c′) of area A′ = u₀ A: its angle sum A′ + π
        let ap_pi = pi + u0 * self.area;
        let (sin_alpha, cos_alpha) = self.alpha.sin_cos();
        let (sin_ap, cos_ap) = ap_pi.sin_cos();
        let sin_phi = sin_ap * cos_alpha - cos_ap * sin_alpha;
        let cos_phi = cos_ap * cos_alpha + sin_ap * sin_alpha;
        let k1 = cos_phi + cos_alpha;
        let k2 = sin_phi - sin_alpha * a.dot(b);
        let cos_bp = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
            / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha))
            .clamp(-1.0, 1.0);
        let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
        let cp = cos_bp * a + sin_bp * gram_schmidt(c, a).normalize_or_zero();
        let cos_theta = 1.0 - u1 * (1.0 - cp.dot(b));
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let w = cos_theta * b + sin_theta * gram_schmidt(cp, b).normalize_or_zero();
        w.normalize_or_zero().as_vec3()
    }

    /// The `u` for which [`SphericalTriangle::sample`] returns the direction `w` (in it).
    pub fn invert(&self, w: Vec3) -> Vec2 {
        let (a, b, c) = (self.a, self.b, self.c);
        let w = w.as_dvec3().normalize_or_zero();
        // c′: where the great circle through b and w meets the arc ac
        let mut cp = b.cross(w).cross(c.cross(a)).normalize_or_zero();
        if cp.dot(a + c) < 0.0 {
            cp = -cp;
        }
        let u0 = if a.dot(cp) > 1.0 - 1e-15 {
            0.0
        } else {
            // the area of (a, b, c′) by Van Oosterom & Strackee
            let ap = 2.0
                * a.dot(b.cross(cp))
                    .atan2(1.0 + a.dot(b) + b.dot(cp) + cp.dot(a));
            ap.abs() / self.area
        };
        let den = 1.0 - cp.dot(b);
        let u1 = if den > 0.0 {
            (1.0 - w.dot(b)) / den
        } else {
            0.0
        };
        Vec2::new(u0.clamp(0.0, 1.0) as f32, u1.clamp(0.0, 1.0) as f32)
    }
}

/// The spherical rectangle that a rectangle (corner `s`, perpendicular edges `ex`, `ey`)
/// subtends from a point: Ureña, Fajardo & King's parametrization. In the frame of the
/// rectangle (x along `ex`, y along `ey`, z toward the point's side flipped so the rectangle
/// lies at `z₀ < 0`), `u₀` picks x by the solid angle of the sub-rectangle left of it and `u₁`
/// picks y uniformly in solid angle given x. `u = (0, 0)` maps to the corner `s`, `(1, 0)` to
/// `s + ex`, `(0, 1)` to `s + ey` (the corners of a [`sample_bilinear`] warp).
#[derive(Clone, Copy, Debug)]
pub struct SphericalRectangle {
    origin: DVec3,
    x_axis: DVec3,
    y_axis: DVec3,
    z_axis: DVec3,
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    z0: f64,
    b0: f64,
    b1: f64,
    /// `(cos k, sin k)`, `k = 2π − γ₂ − γ₃`.
    k: (f64, f64),
    area: f64,
}

/// What Ureña's sampling needs of the rectangle `[x0, x1] × [y0, y1]` at `z = z0 < 0` seen from
/// the origin: its solid angle `Ω = Σγᵢ − 2π` (the internal angles' sum), `b0`, `b1` (the z of
/// the normals of the planes through the edges at y0 and y1) and `(cos k, sin k)` for
/// `k = 2π − γ₂ − γ₃`. In this frame the normals of the planes through the origin and each edge
/// have closed forms, `n₀ ∝ (0, z₀, −y₀)`, `n₁ ∝ (−z₀, 0, x₁)`, `n₂ ∝ (0, −z₀, y₁)`,
/// `n₃ ∝ (z₀, 0, −x₀)`, and so do the cosines and sines of the internal angles `γᵢ` between
/// `−nᵢ` and `nᵢ₊₁`: e.g. `cos γ₀ = x₁y₀/(L_{y0} L_{x1})`, `sin γ₀ = |z₀| |c₁₀|/(L_{y0} L_{x1})`
/// with `L_{y0} = √(z₀² + y₀²)` and `c₁₀` the corner `(x₁, y₀, z₀)`. `Ω` is then the argument of
/// `Π (cos γᵢ + i sin γᵢ)` in (0, 2π]: one arctangent, no arccosines.
fn rectangle_angles(
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    z0: f64,
) -> Option<(f64, f64, f64, (f64, f64))> {
    if z0 == 0.0 || x1 <= x0 || y1 <= y0 {
        return None;
    }
    let z2 = z0 * z0;
    let (lx0, lx1) = ((z2 + x0 * x0).sqrt(), (z2 + x1 * x1).sqrt());
    let (ly0, ly1) = ((z2 + y0 * y0).sqrt(), (z2 + y1 * y1).sqrt());
    let corner = |x: f64, y: f64| (x * x + y * y + z2).sqrt();
    let z = z0.abs();
    // (cos γᵢ, sin γᵢ) at the corners (x1, y0), (x1, y1), (x0, y1), (x0, y0)
    let g = [
        (x1 * y0, z * corner(x1, y0), ly0 * lx1),
        (-x1 * y1, z * corner(x1, y1), lx1 * ly1),
        (x0 * y1, z * corner(x0, y1), ly1 * lx0),
        (-x0 * y0, z * corner(x0, y0), lx0 * ly0),
    ]
    .map(|(c, s, l)| (c / l, s / l));
    let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let g23 = mul(g[2], g[3]);
    let all = mul(mul(g[0], g[1]), g23);
    let tau = 2.0 * std::f64::consts::PI;
    let mut omega = all.1.atan2(all.0);
    if omega <= 0.0 {
        omega += tau;
    }
    // e^{ik} = e^{−i(γ₂+γ₃)}
    Some((omega, -y0 / ly0, y1 / ly1, (g23.0, -g23.1)))
}

impl SphericalRectangle {
    /// `None` when `p` lies on the rectangle's plane (no solid angle).
    pub fn new(s: Vec3, ex: Vec3, ey: Vec3, p: Vec3) -> Option<SphericalRectangle> {
        let (s, ex, ey, p) = (s.as_dvec3(), ex.as_dvec3(), ey.as_dvec3(), p.as_dvec3());
        let (exl, eyl) = (ex.length(), ey.length());
        let x_axis = ex / exl;
        let y_axis = ey / eyl;
        let mut z_axis = x_axis.cross(y_axis);
        let d = s - p;
        let (x0, y0) = (d.dot(x_axis), d.dot(y_axis));
        let mut z0 = d.dot(z_axis);
        if z0 > 0.0 {
            z0 = -z0;
            z_axis = -z_axis;
        }
        if z0 == 0.0 {
            return None;
        }
        let (x1, y1) = (x0 + exl, y0 + eyl);
        let (area, b0, b1, k) = rectangle_angles(x0, y0, x1, y1, z0)?;
        (area > 0.0).then_some(SphericalRectangle {
            origin: p,
            x_axis,
            y_axis,
            z_axis,
            x0,
            y0,
            x1,
            y1,
            z0,
            b0,
            b1,
            k,
            area,
        })
    }

    /// Its solid angle.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The point on the rectangle (world space) in the direction sampled uniformly in solid angle.
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let (u0, u1) = (u.x as f64, u.y as f64);
        let (z0, b0, b1) = (self.z0, self.b0, self.b1);
        // au = u₀Ω + k, by the angle sum of (u₀Ω) and k
        let (sin_a, cos_a) = (u0 * self.area).sin_cos();
        let (cos_k, sin_k) = self.k;
        let (sin_au, cos_au) = (sin_a * cos_k + cos_a * sin_k, cos_a * cos_k - sin_a * sin_k);
        let fu = (cos_au * b0 - b1) / sin_au;
        let cu = (1.0 / (fu * fu + b0 * b0).sqrt())
            .copysign(fu)
            .clamp(-1.0 + 1e-15, 1.0 - 1e-15);
        let xu = (-(cu * z0) / (1.0 - cu * cu).max(0.0).sqrt()).clamp(self.x0, self.x1);
        let d = (xu * xu + z0 * z0).sqrt();
        let h0 = self.y0 / (d * d + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d * d + self.y1 * self.y1).sqrt();
        let hv = h0 + u1 * (h1 - h0);
        let yv = if hv * hv < 1.0 - 1e-12 {
            (hv * d / (1.0 - hv * hv).sqrt()).clamp(self.y0, self.y1)
        } else {
            self.y1
        };
        (self.origin + xu * self.x_axis + yv * self.y_axis + z0 * self.z_axis).as_vec3()
    }

    /// The `u` for which [`SphericalRectangle::sample`] returns the point `q` of the rectangle:
    /// `u₀` = the solid angle of the part of the rectangle left of `q` over the whole, `u₁` from
    /// `h = y/√(d² + y²)` linear between its values at the rectangle's two y edges.
    pub fn invert(&self, q: Vec3) -> Vec2 {
        let v = q.as_dvec3() - self.origin;
        let xu = v.dot(self.x_axis).clamp(self.x0, self.x1);
        let yv = v.dot(self.y_axis).clamp(self.y0, self.y1);
        let z0 = self.z0;
        let u0 = if xu <= self.x0 {
            0.0
        } else {
            rectangle_angles(self.x0, self.y0, xu, self.y1, z0).map_or(0.0, |a| a.0) / self.area
        };
        let d2 = xu * xu + z0 * z0;
        let h = |y: f64| y / (d2 + y * y).sqrt();
        let (h0, h1) = (h(self.y0), h(self.y1));
        let u1 = if h1 != h0 {
            (h(yv) - h0) / (h1 - h0)
        } else {
            0.0
        };
        Vec2::new(u0.clamp(0.0, 1.0) as f32, u1.clamp(0.0, 1.0) as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sampling then inverting gives back `u`; sampled directions hit the shape; a rectangle's
    /// solid angle is the sum of its two triangles'.
    #[test]
    fn spherical_warps_round_trip_and_stay_on_their_shape() {
        let v = [
            Vec3::new(-1.0, 0.2, -2.0),
            Vec3::new(1.5, -0.3, -2.5),
            Vec3::new(0.1, 1.2, -1.8),
        ];
        let (s, ex, ey) = (
            Vec3::new(-1.0, 2.0, -1.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.5),
        );
        for p in [
            Vec3::ZERO,
            Vec3::new(0.3, 1.9, -0.2),
            Vec3::new(5.0, -1.0, 3.0),
        ] {
            let tri = SphericalTriangle::new(v, p).unwrap();
            let rect = SphericalRectangle::new(s, ex, ey, p).unwrap();
            let halves = SphericalTriangle::new([s, s + ex, s + ex + ey], p)
                .unwrap()
                .area()
                + SphericalTriangle::new([s, s + ex + ey, s + ey], p)
                    .unwrap()
                    .area();
            assert!((rect.area() - halves).abs() < 1e-9 * halves, "{p}");
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
            for i in 1..16 {
                for j in 1..16 {
                    let u = Vec2::new(i as f32 / 16.0, j as f32 / 16.0);
                    let w = tri.sample(u);
                    let back = tri.invert(w);
                    assert!((back - u).abs().max_element() < 2e-4, "{p} {u} -> {back}");
                    // the ray p + t w meets the triangle's plane inside the triangle
                    let t = n.dot(v[0] - p) / n.dot(w);
                    let q = p + w * t;
                    let (a, b) = ((v[1] - v[0]).cross(q - v[0]), (v[2] - v[1]).cross(q - v[1]));
                    let c = (v[0] - v[2]).cross(q - v[2]);
                    assert!(t > 0.0 && a.dot(n) > -1e-4 && b.dot(n) > -1e-4 && c.dot(n) > -1e-4);
                    let q = rect.sample(u);
                    let (x, y) = (
                        (q - s).dot(ex) / ex.length_squared(),
                        (q - s).dot(ey) / ey.length_squared(),
                    );
                    assert!((-1e-5..=1.0 + 1e-5).contains(&x) && (-1e-5..=1.0 + 1e-5).contains(&y));
                    assert!((q - s).dot(ex.cross(ey)).abs() < 1e-4);
                    let back = rect.invert(q);
                    assert!((back - u).abs().max_element() < 2e-4, "{p} {u} -> {back}");
                    let wts = [0.3, 1.0, 0.05, 2.0];
                    let b = sample_bilinear(u, wts);
                    assert!((invert_bilinear(b, wts) - u).abs().max_element() < 1e-5);
                }
            }
        }
        // the corners of u: (x, 0) → b, (0, 1) → a, (1, 1) → c
        let tri = SphericalTriangle::new(v, Vec3::ZERO).unwrap();
        let [a, b, c] = tri.vertices().map(|d| d.as_vec3());
        assert!((tri.sample(Vec2::new(0.3, 0.0)) - b).length() < 1e-5);
        assert!((tri.sample(Vec2::new(0.0, 1.0)) - a).length() < 1e-5);
        assert!((tri.sample(Vec2::new(1.0, 1.0)) - c).length() < 1e-5);
        assert!(SphericalTriangle::new(v, v[0]).is_none());
    }
}
