//! The lights of a scene and how they are sampled: the emitters (emissive triangles, and pairs
//! of them that form a rectangle) and the environment when it is not black.
//!
//! - **Emitters** are one-sided: an emitter sends `Le` to the side its counter-clockwise normal
//!   `n_l` points to. Two emissive triangles of the same emission that share their diagonal and
//!   together make a rectangle (checked at load with a tolerance) are one emitter, so one 2D
//!   point stratifies the whole rectangle. (A parallelogram that is not a rectangle stays two
//!   triangles: Ureña's spherical-rectangle map needs perpendicular edges.)
//! - **A point on an emitter** ([`LightPoints`], `--light-points`), seen from a receiving point
//!   `x` with shading normal `n`:
//!   - `area`: uniform by area (Heitz's triangle map, or the rectangle's `s + u₀e_x + u₁e_y`),
//!     pdf `1/A`, per solid angle `p_ω = d²/(A cosθ_l)`, `cosθ_l = n_l·(x − y)/d > 0`;
//!   - `solid-angle`: uniform in the solid angle `Ω` the emitter subtends
//!     ([`SphericalTriangle`], [`SphericalRectangle`]), `p_ω = 1/Ω`;
//!   - `projected`: the solid-angle map with `u` first warped bilinearly by the receiver's
//!     cosine at the domain's corners, `w = max(0.01, |n·ω_corner|)` (pbrt-v4's approximation of
//!     projected solid angle), `p_ω = bilinear(u⁻¹(ω))/Ω`.
//!
//!   Both spherical methods fall back to area sampling where the spherical math loses accuracy,
//!   as pbrt-v4 does: a triangle subtending less than [`MIN_TRIANGLE_SOLID_ANGLE`] (3·10⁻⁴ sr)
//!   or more than [`MAX_SOLID_ANGLE`] (6.22 sr), a rectangle less than
//!   [`MIN_RECTANGLE_SOLID_ANGLE`] (10⁻⁴ sr) or more than 6.22 sr. The pdf of a point is always
//!   the pdf of the method that sampled it from that receiver (the same test decides).
//! - **The environment** ([`Environment`]: a constant radiance, or an HDR map) is sampled by a
//!   cosine distribution about `n`, `p_ω = cosθ/π` (zero below): always for a constant one (under
//!   a diffuse BSDF `f cosθ / p_ω = kd`, so a white furnace has no variance), and for a map with
//!   `--light-points area` (the strategy that ignores where a light's radiance comes from). With
//!   `solid-angle` or `projected` a map is sampled by its luminance ([`EnvMap::sample`], the
//!   piecewise-constant lat-long distribution with its sinθ).
//! - **Which light** ([`LightChoice`], `--light-choice`): `uniform` (every light of positive
//!   power alike), `power` (`Φ = π A lum(Le)` for an emitter, `πR² ∫lum(L_env) dω` for the
//!   environment seen by a scene of bounding radius `R`, pbrt's estimate), or `tree`: the
//!   environment by power against all emitters, then a light BVH ([`LightTree`]: Conty Estevez
//!   & Kulla 2018, pbrt-v4's `BVHLightSampler`) descended from the root, each child chosen in
//!   proportion to an importance bound from the receiving point (power, distance, the emitters'
//!   normal cone and the receiver's cosine).
//!
//!   Every choice is exact for the values drawn: it splits the 2²⁴ units of `u`'s resolution in
//!   whole units (a [`Discrete`] for uniform and power; the tree splits its node's range at each
//!   level in proportion to the two importances, at least one unit to a child of positive
//!   importance while the range has two), so the pmf returned for a light is exactly the
//!   frequency with which it is chosen, also from a given point. A light whose share rounds to
//!   no unit (a tree node's range down to one unit, below ~2⁻²⁴ of the importance at that point)
//!   has pmf 0 there: MIS then gives its BSDF-found light full weight (unbiased); with NEE alone
//!   its contribution, below 2⁻²⁴ of the light at that point by its bound, is missed.
//!
//! Every pdf this module returns is per unit solid angle at the receiving point and includes
//! the choice probability. [`Lights::light_of`] maps a BVH-order primitive to its emitter, so a
//! BSDF-sampled ray that hits an emitter finds the light pdf of the same path for MIS.

use crate::environment::{EnvMap, Environment};
use crate::math::Frame;
use crate::sampling::{
    bilinear_pdf, cosine_hemisphere_pdf, sample_bilinear, sample_cosine_hemisphere,
    sample_uniform_triangle, Discrete, SphericalRectangle, SphericalTriangle, UNIT_BITS,
};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::sync::OnceLock;

mod tree;
pub use tree::{LightBounds, LightTree};

/// How light is found at a vertex (the `--lights` flag): the third axis of variance reduction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum LightStrategy {
    /// BSDF sampling only: emission counts when a sampled ray happens to hit it.
    Bsdf,
    /// Next-event estimation: sample one light per vertex and trace a shadow ray; emission
    /// hit by BSDF-sampled rays after the camera ray is not added.
    Nee,
    /// Both, weighted by the power heuristic (multiple importance sampling).
    #[default]
    Mis,
}

impl std::fmt::Display for LightStrategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&crate::names::value_name(self))
    }
}

/// How a point on an emitter is chosen (the `--light-points` flag).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum LightPoints {
    /// Uniform by area, the pdf converted to solid angle.
    Area,
    /// Uniform in the solid angle the emitter subtends (spherical triangles and rectangles).
    SolidAngle,
    /// The solid-angle map warped by the receiver's cosine at the corners (bilinear).
    Projected,
    /// Per light and receiver: `projected` where the light looks large from the receiver
    /// (`A cosθ_l/d² ≥` [`AUTO_SOLID_ANGLE`] at its centre), `area` where it looks small and
    /// the two place points alike at a fraction of the cost.
    #[default]
    Auto,
}

impl std::fmt::Display for LightPoints {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&crate::names::value_name(self))
    }
}

/// How the light of a vertex is chosen (the `--light-choice` flag).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum LightChoice {
    /// Every light of positive power alike.
    Uniform,
    /// In proportion to power.
    Power,
    /// A light BVH: by an importance bound from the receiving point.
    #[default]
    Tree,
}

impl std::fmt::Display for LightChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&crate::names::value_name(self))
    }
}

/// Below this solid angle (sr) a triangle is sampled by area (pbrt-v4's threshold).
pub const MIN_TRIANGLE_SOLID_ANGLE: f64 = 3e-4;
/// Below this solid angle (sr) a rectangle is sampled by area (pbrt-v4's threshold).
pub const MIN_RECTANGLE_SOLID_ANGLE: f64 = 1e-4;
/// Above this solid angle (sr, 99 % of the hemisphere) an emitter is sampled by area.
pub const MAX_SOLID_ANGLE: f64 = 6.22;

/// `--light-points auto` samples an emitter by projected solid angle from a receiver where its
/// solid angle, estimated as `A cosθ_l/d²` from its centre, is at least this (sr), and by area
/// below. Chosen by efficiency, 1/(MSE × time), over the shipped scenes at 64 spp against
/// projected points everywhere (`tools/readme_numbers.py --only efficiency` has the table):
/// 0.02 sr gained 1.0–1.4× by scene, 0.05 up to 1.5×, 0.1 1.0–1.5× (geometric mean 1.24×,
/// the best; never below projected), 0.2 lost 9% on the night hall (its lamps hang close to
/// the walls they light) and 0.4 21%. The Cornell box's light subtends ~0.05 sr from its floor.
pub const AUTO_SOLID_ANGLE: f32 = 0.1;

/// Index in the primitive → emitter map of a primitive that is no light.
const NO_LIGHT: u32 = u32::MAX;
/// The units of `u`'s resolution that a choice splits.
const UNITS: u32 = 1 << UNIT_BITS;

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
    fn corners(&self) -> ([Vec3; 4], usize) {
        match self.shape {
            Shape::Triangle(v) => ([v[0], v[1], v[2], v[2]], 3),
            Shape::Rectangle { s, ex, ey } => ([s, s + ex, s + ey, s + ex + ey], 4),
        }
    }

    /// Its centre (the mean of its corners).
    fn centre(&self) -> Vec3 {
        match self.shape {
            Shape::Triangle(v) => (v[0] + v[1] + v[2]) / 3.0,
            Shape::Rectangle { s, ex, ey } => s + 0.5 * (ex + ey),
        }
    }

    /// The point at `u` uniform by area.
    fn point_by_area(&self, u: Vec2) -> Vec3 {
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
enum Spherical {
    Triangle(SphericalTriangle),
    Rectangle(SphericalRectangle),
}

impl Spherical {
    /// `None`: sample `e` by area from `p` (too small or too large a solid angle, or none).
    fn of(e: &Emitter, p: Vec3) -> Option<Spherical> {
        match e.shape {
            Shape::Triangle(v) => SphericalTriangle::new(v, p)
                .filter(|t| (MIN_TRIANGLE_SOLID_ANGLE..=MAX_SOLID_ANGLE).contains(&t.area()))
                .map(Spherical::Triangle),
            Shape::Rectangle { s, ex, ey } => SphericalRectangle::new(s, ex, ey, p)
                .filter(|r| (MIN_RECTANGLE_SOLID_ANGLE..=MAX_SOLID_ANGLE).contains(&r.area()))
                .map(Spherical::Rectangle),
        }
    }

    fn area(&self) -> f32 {
        match self {
            Spherical::Triangle(t) => t.area() as f32,
            Spherical::Rectangle(r) => r.area() as f32,
        }
    }

    /// The cosine weights of a bilinear warp at the corners of `u` (see the warps' docs).
    fn weights(&self, e: &Emitter, p: Vec3, n: Vec3) -> [f32; 4] {
        let w = |v: Vec3| n.dot((v - p).normalize_or_zero()).abs().max(0.01);
        match (self, e.shape) {
            (Spherical::Triangle(_), Shape::Triangle(v)) => [w(v[1]), w(v[1]), w(v[0]), w(v[2])],
            (_, Shape::Rectangle { s, ex, ey }) => [w(s), w(s + ex), w(s + ey), w(s + ex + ey)],
            _ => [1.0; 4],
        }
    }
}

/// A sampled light direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the receiving point toward the light.
    pub wi: Vec3,
    /// Distance to the sampled point (infinite for the environment).
    pub dist: f32,
    /// Radiance arriving along `-wi` if nothing is in between.
    pub le: Vec3,
    /// Probability density of `wi` per unit solid angle, choice included.
    pub pdf: f32,
}

/// All lights of a scene, and the distributions that choose among them.
#[derive(Debug, Default)]
pub struct Lights {
    /// The emitters (triangles and rectangles), in BVH order of their first primitive.
    pub emitters: Vec<Emitter>,
    /// The environment (black: it is no light).
    pub environment: Environment,
    /// `light_index[prim]`: the emitter of BVH-order triangle `prim`, or [`NO_LIGHT`].
    light_index: Vec<u32>,
    /// Choice by power, and uniform: each emitter, then the environment (last).
    by_power: Discrete,
    uniform: Discrete,
    /// The environment's units in the tree choice (by power against all emitters).
    environment_units: u32,
    /// The light BVH, built at its first use.
    tree: OnceLock<LightTree>,
}

pub use crate::math::luminance;

impl Lights {
    /// The lights of a scene of `primitives` triangles: its emissive triangles (each knowing its
    /// BVH-order primitive; pairs that make a rectangle become one emitter), and the
    /// `environment` (a radiance, or an [`Environment`]) lighting a scene of bounding radius
    /// `radius`. Err with more than 2²⁴ lights (see [`Discrete`]).
    pub fn build(
        triangles: Vec<Emitter>,
        primitives: usize,
        environment: impl Into<Environment>,
        radius: f32,
    ) -> Result<Lights, String> {
        let environment = environment.into();
        let emitters = pair_rectangles(triangles);
        let mut light_index = vec![NO_LIGHT; primitives];
        for (i, e) in emitters.iter().enumerate() {
            for &prim in e.prims.iter().filter(|&&p| p != NO_LIGHT) {
                light_index[prim as usize] = i as u32;
            }
        }
        let mut power: Vec<f64> = emitters.iter().map(|e| e.power() as f64).collect();
        let env_power = (PI * radius * radius) as f64 * environment.luminance_integral();
        power.push(env_power);
        let ones: Vec<f64> = power
            .iter()
            .map(|&p| if p > 0.0 { 1.0 } else { 0.0 })
            .collect();
        let emitter_power: f64 = power[..emitters.len()].iter().sum();
        let environment_units = Discrete::new(&[env_power, emitter_power])?.units(0);
        Ok(Lights {
            emitters,
            environment,
            light_index,
            by_power: Discrete::new(&power)?,
            uniform: Discrete::new(&ones)?,
            environment_units,
            tree: OnceLock::new(),
        })
    }

    /// Number of emitters.
    pub fn len(&self) -> usize {
        self.emitters.len()
    }

    /// True when the scene has no emitter.
    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    /// True when something can be sampled (an emitter, or a non-black environment).
    pub fn any(&self) -> bool {
        self.by_power.any()
    }

    /// The emitter that BVH-order triangle `prim` belongs to, if it emits.
    #[inline]
    pub fn light_of(&self, prim: u32) -> Option<u32> {
        match self.light_index.get(prim as usize) {
            Some(&i) if i != NO_LIGHT => Some(i),
            _ => None,
        }
    }

    /// The light BVH (built at the first call).
    pub fn tree(&self) -> &LightTree {
        self.tree.get_or_init(|| LightTree::build(&self.emitters))
    }

    /// How lights are sampled with `points` and `choice`.
    pub fn sampler(&self, points: LightPoints, choice: LightChoice) -> LightSampler<'_> {
        LightSampler {
            lights: self,
            points,
            choice,
            tree: (choice == LightChoice::Tree && !self.emitters.is_empty()).then(|| self.tree()),
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
fn pair_rectangles(triangles: Vec<Emitter>) -> Vec<Emitter> {
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

/// How the lights are sampled in one render: the points method, the choice, and the tree.
#[derive(Clone, Copy, Debug)]
pub struct LightSampler<'a> {
    lights: &'a Lights,
    points: LightPoints,
    choice: LightChoice,
    tree: Option<&'a LightTree>,
}

/// A chosen light: emitter `i`, or the environment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Chosen {
    Emitter(u32),
    Environment,
}

impl LightSampler<'_> {
    /// True when something can be sampled.
    pub fn any(&self) -> bool {
        self.lights.any()
    }

    /// The light chosen by `u` for a receiver at `p` with normal `n`, and its probability
    /// (exactly the frequency of this choice from `p`). `None`: nothing to choose from here.
    #[inline]
    pub fn choose(&self, p: Vec3, n: Vec3, u: f32) -> Option<(Chosen, f32)> {
        let l = self.lights;
        let as_light = |i: usize| {
            if i < l.emitters.len() {
                Chosen::Emitter(i as u32)
            } else {
                Chosen::Environment
            }
        };
        match (self.choice, self.tree) {
            (LightChoice::Power, _) | (LightChoice::Tree, None) => l
                .by_power
                .sample(u)
                .map(|i| (as_light(i), l.by_power.pmf(i))),
            (LightChoice::Uniform, _) => {
                l.uniform.sample(u).map(|i| (as_light(i), l.uniform.pmf(i)))
            }
            (LightChoice::Tree, Some(tree)) => {
                let k = ((u * UNITS as f32) as u32).min(UNITS - 1);
                if k < l.environment_units {
                    return Some((
                        Chosen::Environment,
                        l.environment_units as f32 / UNITS as f32,
                    ));
                }
                let (i, units) = tree.choose(p, n, k, l.environment_units..UNITS)?;
                Some((Chosen::Emitter(i), units as f32 / UNITS as f32))
            }
        }
    }

    /// The probability that [`LightSampler::choose`] picks emitter `i` for `(p, n)`.
    #[inline]
    pub fn pmf(&self, p: Vec3, n: Vec3, i: u32) -> f32 {
        let l = self.lights;
        match (self.choice, self.tree) {
            (LightChoice::Power, _) | (LightChoice::Tree, None) => l.by_power.pmf(i as usize),
            (LightChoice::Uniform, _) => l.uniform.pmf(i as usize),
            (LightChoice::Tree, Some(tree)) => {
                tree.units(p, n, i, l.environment_units..UNITS) as f32 / UNITS as f32
            }
        }
    }

    /// The probability of choosing the environment.
    #[inline]
    pub fn environment_pmf(&self) -> f32 {
        let l = self.lights;
        let last = l.emitters.len();
        match (self.choice, self.tree) {
            (LightChoice::Power, _) | (LightChoice::Tree, None) => l.by_power.pmf(last),
            (LightChoice::Uniform, _) => l.uniform.pmf(last),
            (LightChoice::Tree, Some(_)) => l.environment_units as f32 / UNITS as f32,
        }
    }

    /// Sample a light for the point `p` with shading normal `n` (on the side light is gathered
    /// from): `u_choose` picks the light, `u` the point on it (or the environment direction).
    /// `None` when nothing is sampled or the point sees the back of the chosen emitter.
    #[inline]
    pub fn sample(&self, p: Vec3, n: Vec3, u_choose: f32, u: Vec2) -> Option<LightSample> {
        let (chosen, pmf) = self.choose(p, n, u_choose)?;
        match chosen {
            Chosen::Emitter(i) => {
                let e = &self.lights.emitters[i as usize];
                let (y, pdf) = self.point_on(e, p, n, u)?;
                let d = y - p;
                let dist = d.length();
                if dist <= 0.0 || pdf.is_nan() || pdf <= 0.0 || !pdf.is_finite() {
                    return None;
                }
                Some(LightSample {
                    wi: d / dist,
                    dist,
                    le: e.emission,
                    pdf: pmf * pdf,
                })
            }
            Chosen::Environment => {
                if let Some(m) = self.map_sampled() {
                    let (wi, le, pdf) = m.sample(u)?;
                    return Some(LightSample {
                        wi,
                        dist: f32::INFINITY,
                        le,
                        pdf: pmf * pdf,
                    });
                }
                let local = sample_cosine_hemisphere(u);
                let pdf = pmf * cosine_hemisphere_pdf(local.z);
                let wi = Frame::from_normal(n).to_world(local);
                (pdf > 0.0).then(|| LightSample {
                    wi,
                    dist: f32::INFINITY,
                    le: self.lights.environment.radiance(wi),
                    pdf,
                })
            }
        }
    }

    /// A point on emitter `e` seen from `p` (normal `n`) at `u`, and its pdf per solid angle
    /// (without the choice). `None` when `p` sees the emitter's back.
    #[inline]
    fn point_on(&self, e: &Emitter, p: Vec3, n: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
        let (corner, _) = e.corners();
        if e.n.dot(p - corner[0]) <= 0.0 {
            return None; // behind the emitting side (or on its plane)
        }
        let Some(sph) = self.spherical(e, p) else {
            let y = e.point_by_area(u);
            return Some((y, area_pdf(e, p, y)));
        };
        let (u, warp) = if self.points != LightPoints::SolidAngle {
            let w = sph.weights(e, p, n);
            let v = sample_bilinear(u, w);
            (v, bilinear_pdf(v, w))
        } else {
            (u, 1.0)
        };
        let y = match &sph {
            Spherical::Triangle(t) => {
                let w = t.sample(u);
                let den = e.n.dot(w);
                if den >= 0.0 {
                    return None;
                }
                p + w * (e.n.dot(corner[0] - p) / den)
            }
            Spherical::Rectangle(r) => r.sample(u),
        };
        Some((y, warp / sph.area()))
    }

    /// The pdf per solid angle with which [`LightSampler::sample`] at `p` (normal `n`) returns
    /// the point `y` of emitter `i` (0 when `p` sees its back).
    #[inline]
    pub fn pdf(&self, i: u32, p: Vec3, n: Vec3, y: Vec3) -> f32 {
        let e = &self.lights.emitters[i as usize];
        let (corner, _) = e.corners();
        if e.n.dot(p - corner[0]) <= 0.0 {
            return 0.0;
        }
        let pmf = self.pmf(p, n, i);
        if pmf == 0.0 {
            return 0.0;
        }
        let Some(sph) = self.spherical(e, p) else {
            return pmf * area_pdf(e, p, y);
        };
        let warp = if self.points != LightPoints::SolidAngle {
            let u = match &sph {
                Spherical::Triangle(t) => t.invert((y - p).normalize_or_zero()),
                Spherical::Rectangle(r) => r.invert(y),
            };
            // the bilinear density at the domain point the spherical map took (the warped u)
            bilinear_pdf(u, sph.weights(e, p, n))
        } else {
            1.0
        };
        pmf * warp / sph.area()
    }

    /// The pdf per solid angle with which [`LightSampler::sample`] at a point `p` of shading
    /// normal `n` returns the environment direction `wi`.
    #[inline]
    pub fn environment_pdf(&self, n: Vec3, wi: Vec3) -> f32 {
        match self.map_sampled() {
            Some(m) => self.environment_pmf() * m.pdf(wi),
            None => self.environment_pmf() * cosine_hemisphere_pdf(n.dot(wi)),
        }
    }

    /// The spherical domain in which a point on `e` is placed from `p`, or `None` to place it
    /// by area: the one decision [`LightSampler::point_on`] and [`LightSampler::pdf`] share.
    #[inline]
    fn spherical(&self, e: &Emitter, p: Vec3) -> Option<Spherical> {
        match self.points {
            LightPoints::Area => None,
            LightPoints::Auto => {
                let d = e.centre() - p;
                let d2 = d.length_squared();
                let looks = e.area * (-e.n.dot(d)).max(0.0) / (d2 * d2.sqrt());
                if looks >= AUTO_SOLID_ANGLE {
                    Spherical::of(e, p)
                } else {
                    None
                }
            }
            LightPoints::SolidAngle | LightPoints::Projected => Spherical::of(e, p),
        }
    }

    /// The environment map, when it is sampled by its luminance (a map, and light points other
    /// than `area`); `None` when the environment is sampled by the cosine.
    #[inline]
    fn map_sampled(&self) -> Option<&EnvMap> {
        match self.points {
            LightPoints::Area => None,
            _ => self.lights.environment.map(),
        }
    }
}

/// The pdf per solid angle at `p` of the point `y` of `e` sampled uniformly by area.
#[inline]
fn area_pdf(e: &Emitter, p: Vec3, y: Vec3) -> f32 {
    let d = y - p;
    let dist2 = d.length_squared();
    let cos_l = -e.n.dot(d) / dist2.sqrt();
    if cos_l <= 0.0 || dist2 <= 0.0 {
        return 0.0;
    }
    dist2 / (e.area * cos_l)
}
