//! The random-dimension layout of a path sample, named once: which decision each dimension of
//! the sampler feeds. A path sample draws
//!
//! | dimensions | decision |
//! |---|---|
//! | [`CAMERA_DIMS`] | the point in the pixel (2D) |
//! | [`BOUNCE_DIMS`], at every vertex after the camera | light choice (1D), point on the light (2D), lobe choice (1D), direction (2D), Russian roulette (1D) |
//! | then [`GUIDE_DIMS`], with `--directions guided` only | guide or BSDF (1D), guided direction (2D) |
//!
//! The guide's dimensions come last in a bounce so that every other dimension keeps its place in
//! the bounce (the first bounce's indices are those of every other strategy); a guided render
//! strides 8 dimensions per bounce, the others 5.
//! The light dimensions come first because next-event estimation happens first at a vertex.
//! Every bounce keeps all of its dimensions, used or not: a value the bounce cannot use (the
//! light's under `--lights bsdf`, the light choice where one light can be chosen, the lobe
//! choice of a BSDF of one lobe, the roulette before it starts) is skipped, not drawn, and its
//! index kept, so a dimension index means the same decision in every sample — what
//! stratification needs. [`CameraSample::draw`] and
//! [`BounceSample::draw`] are the only code that draws them; tests and benchmarks walk the same
//! tables.

use super::Sampler;
use glam::Vec2;

/// One dimension of the layout: its size and what it decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    /// A 1D dimension and what it decides.
    One(&'static str),
    /// A 2D dimension and what it decides.
    Two(&'static str),
}

/// The camera sample's dimensions.
pub const CAMERA_DIMS: [Dim; 1] = [Dim::Two("pixel position")];

/// The dimensions of every bounce, in the order they are drawn.
pub const BOUNCE_DIMS: [Dim; 5] = [
    Dim::One("light choice"),
    Dim::Two("point on the light"),
    Dim::One("lobe choice"),
    Dim::Two("direction"),
    Dim::One("russian roulette"),
];

/// The dimensions a bounce of `--directions guided` draws after [`BOUNCE_DIMS`].
pub const GUIDE_DIMS: [Dim; 2] = [Dim::One("guide or bsdf"), Dim::Two("guided direction")];

/// The numbers of the camera ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSample {
    /// Position inside the pixel, `[0,1)²`.
    pub pixel: Vec2,
}

impl CameraSample {
    /// Draw [`CAMERA_DIMS`].
    #[inline]
    pub fn draw<S: Sampler>(s: &mut S) -> Self {
        CameraSample { pixel: s.next_2d() }
    }
}

/// Which light values a bounce draws ([`BounceSample::draw_needed`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightValues {
    /// None: the path takes no light sample (BSDF sampling only, or no light), or not at this
    /// vertex (a mirror's or glass's).
    None,
    /// The point on the light (or the environment's direction), not the choice: one light
    /// can be chosen, whatever the choice's value ([`crate::lights::LightSampler::chooses`]).
    Point,
    /// The light choice and the point.
    ChoiceAndPoint,
}

impl LightValues {
    /// The values a path draws that takes light samples (`sample`) from a chooser that
    /// `chooses` between lights or not.
    pub fn of(sample: bool, chooses: bool) -> LightValues {
        match (sample, chooses) {
            (false, _) => LightValues::None,
            (true, false) => LightValues::Point,
            (true, true) => LightValues::ChoiceAndPoint,
        }
    }
}

/// The numbers of one bounce.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BounceSample {
    /// Chooses the light for next-event estimation.
    pub light: f32,
    /// Places the point on the light (or the environment direction).
    pub light_point: Vec2,
    /// Picks the lobe of the Phong mixture.
    pub lobe: f32,
    /// Places the direction within the lobe.
    pub direction: Vec2,
    /// Decides Russian roulette.
    pub roulette: f32,
    /// Chooses between the guide and the BSDF (guided directions only; else 0).
    pub guide: f32,
    /// Places the guided direction (guided directions only; else 0).
    pub guided_direction: Vec2,
}

impl BounceSample {
    /// Draw [`BOUNCE_DIMS`], in their order. Without `lights` (BSDF sampling only) the light
    /// dimensions are skipped, not drawn, and read as zero: the layout stays the same.
    #[inline(always)]
    pub fn draw<S: Sampler>(s: &mut S, lights: bool) -> Self {
        Self::draw_needed(s, LightValues::of(lights, true), true, true, false)
    }

    /// [`BounceSample::draw`] that draws the light values `lights` asks for (the light choice
    /// only where the render's chooser has more than one light to pick from), skips the lobe
    /// choice when `lobe` is false (a BSDF of one lobe) and the roulette value when `roulette`
    /// is false (a bounce before roulette starts). A skipped dimension reads as zero and every
    /// other value is the one `draw` gives: each sampler's value depends on the dimension's
    /// index only, and skipping keeps the index. With `guided` it then draws [`GUIDE_DIMS`] (a
    /// guided render's layout; without, they are not part of the layout and read as zero).
    #[inline(always)]
    pub fn draw_needed<S: Sampler>(
        s: &mut S,
        lights: LightValues,
        lobe: bool,
        roulette: bool,
        guided: bool,
    ) -> Self {
        let light = match lights {
            LightValues::ChoiceAndPoint => s.next_1d(),
            _ => {
                s.skip_1d(1);
                0.0
            }
        };
        let light_point = match lights {
            LightValues::None => {
                s.skip_2d(1);
                Vec2::ZERO
            }
            _ => s.next_2d(),
        };
        let lobe = if lobe {
            s.next_1d()
        } else {
            s.skip_1d(1);
            0.0
        };
        let direction = s.next_2d();
        let roulette = if roulette {
            s.next_1d()
        } else {
            s.skip_1d(1);
            0.0
        };
        let (guide, guided_direction) = if guided {
            (s.next_1d(), s.next_2d())
        } else {
            (0.0, Vec2::ZERO)
        };
        BounceSample {
            light,
            light_point,
            lobe,
            direction,
            roulette,
            guide,
            guided_direction,
        }
    }
}

/// Draw one value per dimension of `dims` (a 1D value in `x`, `y = 0`): how tests and benchmarks
/// walk the layout without knowing what each dimension decides.
pub fn draw_dims<S: Sampler>(s: &mut S, dims: &[Dim]) -> Vec<Vec2> {
    dims.iter()
        .map(|d| match d {
            Dim::One(_) => Vec2::new(s.next_1d(), 0.0),
            Dim::Two(_) => s.next_2d(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::{IndependentSampler, SobolSampler, StratifiedSampler};
    use glam::UVec2;

    /// Two bounces of a path, drawn with every combination of skipped dimensions, against the
    /// same path drawn whole: every value that is drawn is the value the whole path gives it, in
    /// this bounce and the next (issue 24: Sobol skipped one dimension too few for the light's
    /// 1D + 2D values, and every later decision of `--lights bsdf` moved by one).
    fn skipping_keeps_every_later_value<S: Sampler>(sampler: S, name: &str) {
        for i in 0..16 {
            let pixel = UVec2::new(1, 2);
            let mut whole = sampler.clone();
            whole.start_pixel_sample(pixel, i);
            let c = CameraSample::draw(&mut whole);
            let first = BounceSample::draw(&mut whole, true);
            let second = BounceSample::draw(&mut whole, true);
            let kinds = [
                LightValues::None,
                LightValues::Point,
                LightValues::ChoiceAndPoint,
            ];
            for (lights, mask) in kinds
                .into_iter()
                .flat_map(|l| (0..4u32).map(move |m| (l, m)))
            {
                let (lobe, roulette) = (mask & 1 != 0, mask & 2 != 0);
                let mut s = sampler.clone();
                s.start_pixel_sample(pixel, i);
                assert_eq!(CameraSample::draw(&mut s), c, "{name}");
                let a = BounceSample::draw_needed(&mut s, lights, lobe, roulette, false);
                let b = BounceSample::draw_needed(&mut s, lights, lobe, roulette, false);
                for (got, want) in [(a, first), (b, second)] {
                    let what = format!(
                        "{name} sample {i} lights {lights:?} lobe {lobe} roulette {roulette}"
                    );
                    let light = match lights {
                        LightValues::ChoiceAndPoint => want.light,
                        _ => 0.0,
                    };
                    let point = match lights {
                        LightValues::None => Vec2::ZERO,
                        _ => want.light_point,
                    };
                    assert_eq!((got.light, got.light_point), (light, point), "{what}");
                    assert_eq!(got.lobe, if lobe { want.lobe } else { 0.0 }, "{what}");
                    assert_eq!(got.direction, want.direction, "{what}");
                    assert_eq!(
                        got.roulette,
                        if roulette { want.roulette } else { 0.0 },
                        "{what}"
                    );
                }
                // and the bounce after starts where it would have
                assert_eq!(s.next_1d(), whole.clone().next_1d(), "{name}");
            }
        }
    }

    /// A sampler that keeps the trait's default skips (it draws what it skips), as a sampler
    /// written outside the crate would.
    #[derive(Clone)]
    struct DrawsWhatItSkips(SobolSampler);

    impl Sampler for DrawsWhatItSkips {
        fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
            self.0.start_pixel_sample(pixel, index)
        }
        fn next_1d(&mut self) -> f32 {
            self.0.next_1d()
        }
        fn next_2d(&mut self) -> Vec2 {
            self.0.next_2d()
        }
    }

    #[test]
    fn skipped_dimensions_keep_every_later_value() {
        skipping_keeps_every_later_value(IndependentSampler::new(3), "independent");
        skipping_keeps_every_later_value(StratifiedSampler::new(3, 16), "stratified");
        skipping_keeps_every_later_value(SobolSampler::new(3), "sobol");
        skipping_keeps_every_later_value(DrawsWhatItSkips(SobolSampler::new(3)), "default skips");
    }

    /// The structs draw exactly what the tables say.
    #[test]
    fn structs_follow_the_tables() {
        let mut a = StratifiedSampler::new(3, 16);
        let mut b = a.clone();
        for i in 0..16 {
            a.start_pixel_sample(UVec2::new(1, 2), i);
            b.start_pixel_sample(UVec2::new(1, 2), i);
            let c = CameraSample::draw(&mut a);
            let bo = BounceSample::draw(&mut a, true);
            let dims: Vec<Dim> = CAMERA_DIMS.iter().chain(&BOUNCE_DIMS).copied().collect();
            let v = draw_dims(&mut b, &dims);
            assert_eq!(v[0], c.pixel);
            assert_eq!(v[1].x, bo.light);
            assert_eq!(v[2], bo.light_point);
            assert_eq!(v[3].x, bo.lobe);
            assert_eq!(v[4], bo.direction);
            assert_eq!(v[5].x, bo.roulette);
        }
    }
}
