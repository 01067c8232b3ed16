//! Which light: each way of choosing one is a small type with its `choose` and its `pmf` side by
//! side (as pbrt-v4's `lightsamplers.h` keeps them), behind the one trait [`ChooseLight`].
//!
//! Every choice is exact for the values drawn: it splits the 2²⁴ units of `u`'s resolution
//! ([`UNITS`]) in whole units, so the pmf a chooser returns for a light is exactly the frequency
//! with which its `choose` picks that light from the same receiver (see the [module
//! above](super)). The lights are the emitters `0..n` and the environment.
//!
//! A new way of choosing is a type here implementing [`ChooseLight`], an arm of [`Choice`] (the
//! render's chooser, an enum so the path loop's calls stay static), and a [`LightChoice`] value
//! that [`Lights::sampler`] maps to it.

use super::*;

/// A way of choosing a light for a receiver at `p` with shading normal `n`.
pub trait ChooseLight {
    /// The light `u ∈ [0, 1)` picks, and its probability (exactly the frequency of this choice
    /// from `p`); `None`: nothing to choose from here.
    fn choose(&self, p: Vec3, n: Vec3, u: f32) -> Option<(Chosen, f32)>;
    /// The probability that [`ChooseLight::choose`] picks emitter `i` for `(p, n)`.
    fn pmf(&self, p: Vec3, n: Vec3, i: u32) -> f32;
    /// The probability that it picks the environment (the same from every receiver).
    fn environment_pmf(&self) -> f32;
}

/// A choice from a table that does not depend on the receiver: `by power` or `uniform`, over
/// each emitter, then the environment (last).
#[derive(Clone, Copy, Debug)]
pub struct TableChoice<'a> {
    table: &'a Discrete,
    emitters: u32,
}

impl<'a> TableChoice<'a> {
    /// The choice by `table`'s pmf over `emitters` emitters and the environment.
    pub fn new(table: &'a Discrete, emitters: u32) -> Self {
        TableChoice { table, emitters }
    }
}

impl ChooseLight for TableChoice<'_> {
    #[inline]
    fn choose(&self, _: Vec3, _: Vec3, u: f32) -> Option<(Chosen, f32)> {
        let i = self.table.sample(u)?;
        let light = if i < self.emitters as usize {
            Chosen::Emitter(i as u32)
        } else {
            Chosen::Environment
        };
        Some((light, self.table.pmf(i)))
    }

    #[inline]
    fn pmf(&self, _: Vec3, _: Vec3, i: u32) -> f32 {
        self.table.pmf(i as usize)
    }

    #[inline]
    fn environment_pmf(&self) -> f32 {
        self.table.pmf(self.emitters as usize)
    }
}

/// The environment by power against all emitters (its `environment_units` of [`UNITS`]), the
/// rest of the units down the light tree from the receiver.
#[derive(Clone, Copy, Debug)]
pub struct TreeChoice<'a> {
    tree: &'a LightTree,
    environment_units: u32,
}

impl<'a> TreeChoice<'a> {
    /// The choice down `tree`, after the environment's `environment_units`.
    pub fn new(tree: &'a LightTree, environment_units: u32) -> Self {
        TreeChoice {
            tree,
            environment_units,
        }
    }
}

impl ChooseLight for TreeChoice<'_> {
    #[inline]
    fn choose(&self, p: Vec3, n: Vec3, u: f32) -> Option<(Chosen, f32)> {
        let k = ((u * UNITS as f32) as u32).min(UNITS - 1);
        if k < self.environment_units {
            return Some((Chosen::Environment, self.environment_pmf()));
        }
        let (i, units) = self.tree.choose(p, n, k, self.environment_units..UNITS)?;
        Some((Chosen::Emitter(i), units as f32 / UNITS as f32))
    }

    #[inline]
    fn pmf(&self, p: Vec3, n: Vec3, i: u32) -> f32 {
        let units = self.tree.units(p, n, i, self.environment_units..UNITS);
        units as f32 / UNITS as f32
    }

    #[inline]
    fn environment_pmf(&self) -> f32 {
        self.environment_units as f32 / UNITS as f32
    }
}

/// The chooser of a render: one of the types above.
#[derive(Clone, Copy, Debug)]
pub enum Choice<'a> {
    /// By power or uniform.
    Table(TableChoice<'a>),
    /// Down the light tree.
    Tree(TreeChoice<'a>),
}

impl ChooseLight for Choice<'_> {
    #[inline]
    fn choose(&self, p: Vec3, n: Vec3, u: f32) -> Option<(Chosen, f32)> {
        match self {
            Choice::Table(c) => c.choose(p, n, u),
            Choice::Tree(c) => c.choose(p, n, u),
        }
    }

    #[inline]
    fn pmf(&self, p: Vec3, n: Vec3, i: u32) -> f32 {
        match self {
            Choice::Table(c) => c.pmf(p, n, i),
            Choice::Tree(c) => c.pmf(p, n, i),
        }
    }

    #[inline]
    fn environment_pmf(&self) -> f32 {
        match self {
            Choice::Table(c) => c.environment_pmf(),
            Choice::Tree(c) => c.environment_pmf(),
        }
    }
}
