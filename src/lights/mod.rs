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
//!   & Kulla 2018, pbrt-v4's `BVHLightSampler`, built binary and collapsed to four children a
//!   node) descended from the root, each child chosen in proportion to an importance bound from
//!   the receiving point (power, distance, the emitters' normal cone and the receiver's cosine),
//!   the four children's bounds evaluated at once.
//!
//!   Every choice is exact for the values drawn: it splits the 2²⁴ units of `u`'s resolution in
//!   whole units (a [`Discrete`] for uniform and power; the tree splits its node's range at each
//!   level in proportion to the children's importances, at least one unit to each child of
//!   positive importance while the range has enough), so the pmf returned for a light is exactly the
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
    sample_uniform_triangle, Discrete, SphericalRectangle, SphericalTriangle, UNITS,
};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::sync::OnceLock;

mod choice;
mod emitter;
mod sampler;
mod tree;
pub use choice::{Choice, ChooseLight, TableChoice, TreeChoice};
use emitter::{area_pdf, pair_rectangles, Spherical};
pub use emitter::{Emitter, Shape, PAIR_CANDIDATES};
pub use sampler::{Chosen, LightSampler};
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
    /// (`A cosθ_l/d² ≥ 0.1 sr` at its centre, `AUTO_SOLID_ANGLE`), `area` where it looks small
    /// and the two place points alike at a fraction of the cost.
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
    /// Whether exactly one light (an emitter or the environment) has power: then every
    /// chooser picks it whatever its `u` ([`LightSampler::chooses`]).
    one: bool,
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
        let one = power.iter().filter(|&&p| p > 0.0).count() == 1;
        Ok(Lights {
            emitters,
            environment,
            light_index,
            by_power: Discrete::new(&power)?,
            uniform: Discrete::new(&ones)?,
            environment_units,
            one,
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

    /// How lights are sampled with `points` and `choice` (the tree needs an emitter: without
    /// one it chooses by power).
    pub fn sampler(&self, points: LightPoints, choice: LightChoice) -> LightSampler<'_> {
        let n = self.emitters.len() as u32;
        let choice = match choice {
            LightChoice::Uniform => Choice::Table(TableChoice::new(&self.uniform, n)),
            LightChoice::Tree if n > 0 => {
                Choice::Tree(TreeChoice::new(self.tree(), self.environment_units))
            }
            LightChoice::Power | LightChoice::Tree => {
                Choice::Table(TableChoice::new(&self.by_power, n))
            }
        };
        LightSampler {
            lights: self,
            points,
            choice,
        }
    }
}
