//! The emitters: a triangle, or two that make a rectangle (found through their shared diagonal),
//! their points by area and their spherical domains seen from a point (see the
//! [module above](super)).

use super::*;

/// The shape of an emitter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// Vertices in counter-clockwise order about the emitting normal.
    Triangle([Vec3; 3]),
    /// Corner `s` and perpendicular edges `ex`, `ey`.
    Rectangle { s: Vec3, ex: Vec3, ey: Vec3 },
}

/// One emitter: a triangle, or a rectangle made of two.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    pub shape: Shape,
    /// Unit normal of the emitting side.
    pub n: Vec3,
    pub area: f32,
    /// Emitted radiance on the front side.
    pub emission: Vec3,
    /// The BVH-order primitives it is made of (the second is `u32::MAX` for a triangle).
    pub prims: [u32; 2],
}

impl Emitter {
    /// The emissive triangle `v` (BVH-order primitive `prim`) of front radiance `emission`.
    pub fn triangle(prim: u32, v: [Vec3; 3], emission: Vec3) -> Emitter {
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        Emitter {
            shape: Shape::Triangle(v),
            n: c.normalize_or_zero(),
            area: 0.5 * c.length(),
            emission,
            prims: [prim, NO_LIGHT],
        }
    }

    /// The rectangle of triangles `a` and `b` (same emission), if they share a diagonal and
    /// make a rectangle: opposite corners sum to the same point and the edges are perpendicular,
    /// to `1e-5` of the edge lengths plus the f32 rounding of the coordinates (8 ulps of the
    /// largest), so only what is a rectangle up to rounding is sampled as one.
    pub fn rectangle_of(a: &Emitter, b: &Emitter) -> Option<Emitter> {
        let (Shape::Triangle(ta), Shape::Triangle(tb)) = (a.shape, b.shape) else {
            return None;
        };
        if a.emission != b.emission || a.n.dot(b.n) < 1.0 - 1e-5 {
            return None;
        }
        // the shared diagonal: two vertices of a equal to two of b; c is a's third, d b's
        let shared: Vec<usize> = (0..3).filter(|&i| tb.contains(&ta[i])).collect();
        let [i, j] = shared[..] else {
            return None;
        };
        let c = ta[3 - i - j];
        let d = *tb.iter().find(|v| !ta.contains(v))?;
        let (p, q) = (ta[i], ta[j]);
        let (ex, ey) = (p - c, q - c);
        let (lx, ly) = (ex.length(), ey.length());
        let rounding = 8.0
            * f32::EPSILON
            * [c, d, p, q]
                .iter()
                .map(|v| v.abs().max_element())
                .fold(0.0, f32::max);
        let parallelogram = (c + d - p - q).length() <= 1e-5 * (lx + ly) + rounding;
        let perpendicular = ex.dot(ey).abs() <= (1e-5 + rounding / lx.min(ly)) * lx * ly;
        (parallelogram && perpendicular).then(|| Emitter {
            shape: Shape::Rectangle { s: c, ex, ey },
            n: a.n,
            area: ex.cross(ey).length(),
            emission: a.emission,
            prims: [a.prims[0], b.prims[0]],
        })
    }

    /// Its power, `π A lum(Le)` (a one-sided Lambertian emitter).
    pub fn power(&self) -> f32 {
        PI * self.area * luminance(self.emission).max(0.0)
    }

    /// Its corners (3 or 4).
    pub(super) fn corners(&self) -> ([Vec3; 4], usize) {
        match self.shape {
            Shape::Triangle(v) => ([v[0], v[1], v[2], v[2]], 3),
            Shape::Rectangle { s, ex, ey } => ([s, s + ex, s + ey, s + ex + ey], 4),
        }
    }

    /// Its centre (the mean of its corners).
    pub(super) fn centre(&self) -> Vec3 {
        match self.shape {
            Shape::Triangle(v) => (v[0] + v[1] + v[2]) / 3.0,
            Shape::Rectangle { s, ex, ey } => s + 0.5 * (ex + ey),
        }
    }

    /// The point at `u` uniform by area.
    pub(super) fn point_by_area(&self, u: Vec2) -> Vec3 {
        match self.shape {
            Shape::Triangle(v) => {
                let b = sample_uniform_triangle(u);
                v[0] * b.x + v[1] * b.y + v[2] * (1.0 - b.x - b.y)
            }
            Shape::Rectangle { s, ex, ey } => s + ex * u.x + ey * u.y,
        }
    }
}

/// The spherical domain of an emitter seen from a point, where the spherical math is accurate.
pub(super) enum Spherical {
    Triangle(SphericalTriangle),
    Rectangle(SphericalRectangle),
}

impl Spherical {
    /// `None`: sample `e` by area from `p` (too small or too large a solid angle, or none).
    pub(super) fn of(e: &Emitter, p: Vec3) -> Option<Spherical> {
        match e.shape {
            Shape::Triangle(v) => SphericalTriangle::new(v, p)
                .filter(|t| (MIN_TRIANGLE_SOLID_ANGLE..=MAX_SOLID_ANGLE).contains(&t.area()))
                .map(Spherical::Triangle),
            Shape::Rectangle { s, ex, ey } => SphericalRectangle::new(s, ex, ey, p)
                .filter(|r| (MIN_RECTANGLE_SOLID_ANGLE..=MAX_SOLID_ANGLE).contains(&r.area()))
                .map(Spherical::Rectangle),
        }
    }

    pub(super) fn area(&self) -> f32 {
        match self {
            Spherical::Triangle(t) => t.area() as f32,
            Spherical::Rectangle(r) => r.area() as f32,
        }
    }

    /// The cosine weights of a bilinear warp at the corners of `u` (see the warps' docs).
    pub(super) fn weights(&self, e: &Emitter, p: Vec3, n: Vec3) -> [f32; 4] {
        let w = |v: Vec3| n.dot((v - p).normalize_or_zero()).abs().max(0.01);
        match (self, e.shape) {
            (Spherical::Triangle(_), Shape::Triangle(v)) => [w(v[1]), w(v[1]), w(v[0]), w(v[2])],
            (_, Shape::Rectangle { s, ex, ey }) => [w(s), w(s + ex), w(s + ey), w(s + ex + ey)],
            _ => [1.0; 4],
        }
    }
}

/// A triangle looks for its rectangle's other half among at most this many later triangles
/// that share one of its edges: linear time however many share an edge (20,000 emissive
/// triangles fanned around one edge took 5 s when every pair was tried). A rectangle's
/// diagonal is shared by its two halves; an edge shared by more is no rectangle's.
pub const PAIR_CANDIDATES: usize = 8;

/// Merge the pairs of emissive triangles that make a rectangle (see [`Emitter::rectangle_of`]);
/// the others stay triangles. Pairs are found through their shared diagonal, hashed.
pub(super) fn pair_rectangles(triangles: Vec<Emitter>) -> Vec<Emitter> {
    use std::collections::HashMap;
    let key = |a: Vec3, b: Vec3| {
        let (a, b) = (
            a.to_array().map(f32::to_bits),
            b.to_array().map(f32::to_bits),
        );
        if a <= b {
            (a, b)
        } else {
            (b, a)
        }
    };
    let mut by_edge: HashMap<([u32; 3], [u32; 3]), Vec<usize>> = HashMap::new();
    for (k, t) in triangles.iter().enumerate() {
        if let Shape::Triangle(v) = t.shape {
            for (i, j) in [(0, 1), (1, 2), (2, 0)] {
                by_edge.entry(key(v[i], v[j])).or_default().push(k);
            }
        }
    }
    let mut used = vec![false; triangles.len()];
    let mut out = Vec::with_capacity(triangles.len());
    for k in 0..triangles.len() {
        if used[k] {
            continue;
        }
        used[k] = true;
        let Shape::Triangle(v) = triangles[k].shape else {
            continue;
        };
        let mut rect = None;
        'edges: for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            // the bucket lists triangles in order: the candidates are the ones after k
            let bucket = &by_edge[&key(v[i], v[j])];
            let after = bucket.partition_point(|&m| m <= k);
            for &m in bucket[after..].iter().take(PAIR_CANDIDATES) {
                if !used[m] {
                    if let Some(r) = Emitter::rectangle_of(&triangles[k], &triangles[m]) {
                        used[m] = true;
                        rect = Some(r);
                        break 'edges;
                    }
                }
            }
        }
        out.push(rect.unwrap_or(triangles[k]));
    }
    out
}

/// The pdf per solid angle at `p` of the point `y` of `e` sampled uniformly by area.
#[inline]
pub(super) fn area_pdf(e: &Emitter, p: Vec3, y: Vec3) -> f32 {
    let d = y - p;
    let dist2 = d.length_squared();
    let cos_l = -e.n.dot(d) / dist2.sqrt();
    if cos_l <= 0.0 || dist2 <= 0.0 {
        return 0.0;
    }
    dist2 / (e.area * cos_l)
}
