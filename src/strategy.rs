//! The strategy: one point on the grid of variance-reduction axes, and its names.
//!
//! Each axis is an enum deriving `clap::ValueEnum` ([`SamplerKind`], [`Directions`],
//! [`LightStrategy`]); every name — flag values, `SAMPLER+DIRECTIONS+LIGHTS` in experiments,
//! metadata, the `all` list, help text — comes from `ValueEnum::value_variants` and
//! `to_possible_value`, so a new sampler, direction or light strategy is one enum variant. The
//! named presets ([`Preset`]) are points on the grid: the mission's four with BSDF sampling
//! only — independent = (independent, uniform, bsdf), stratified = (stratified, uniform, bsdf),
//! importance = (independent, phong, bsdf), combined = (stratified, phong, bsdf) — and the light
//! axis on top of the best of them: nee = (stratified, phong, nee), mis = (stratified, phong,
//! mis), the default.
//!
//! Light sampling has two more switches, how a point on a light is placed ([`LightPoints`]) and
//! how the light is chosen ([`LightChoice`]); a name that leaves them out takes their defaults
//! (`stratified+phong+mis`), a name that gives them has five parts
//! (`stratified+phong+mis+area+power`), and the presets use the defaults.

#![warn(missing_docs)]

use crate::bsdf::Directions;
use crate::lights::{LightChoice, LightPoints, LightStrategy};
use crate::names::{parse_value, value_name, value_names};
use crate::sampler::SamplerKind;
use clap::ValueEnum;

/// How every random decision of a render is made: one value per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Strategy {
    /// Where the sample points come from.
    pub sampler: SamplerKind,
    /// How bounce directions are chosen.
    pub directions: Directions,
    /// How light is found at a vertex.
    pub lights: LightStrategy,
    /// How a point on a light is placed.
    pub light_points: LightPoints,
    /// How the light of a vertex is chosen.
    pub light_choice: LightChoice,
}

impl Default for Strategy {
    /// The best combination: stratified points, Phong-lobe directions, MIS.
    fn default() -> Self {
        Preset::Mis.strategy()
    }
}

impl Strategy {
    /// Every point of the grid of the first three axes (the light switches at their defaults),
    /// samplers outermost, in the enums' order.
    pub fn all() -> Vec<Strategy> {
        let mut v = Vec::new();
        for &sampler in SamplerKind::value_variants() {
            for &directions in Directions::value_variants() {
                for &lights in LightStrategy::value_variants() {
                    v.push(Strategy::of(sampler, directions, lights));
                }
            }
        }
        v
    }

    /// The point of the grid of these three axes, the light switches at their defaults.
    pub fn of(sampler: SamplerKind, directions: Directions, lights: LightStrategy) -> Strategy {
        Strategy {
            sampler,
            directions,
            lights,
            light_points: LightPoints::default(),
            light_choice: LightChoice::default(),
        }
    }

    /// The preset that names this point, if any.
    pub fn preset(&self) -> Option<Preset> {
        Preset::value_variants()
            .iter()
            .copied()
            .find(|p| p.strategy() == *self)
    }

    /// `SAMPLER+DIRECTIONS+LIGHTS`, then `+POINTS+CHOICE` unless both are the defaults, whether
    /// or not a preset names it.
    pub fn axes_name(&self) -> String {
        let mut s = format!(
            "{}+{}+{}",
            value_name(&self.sampler),
            value_name(&self.directions),
            value_name(&self.lights)
        );
        if (self.light_points, self.light_choice) != Default::default() {
            s += &format!(
                "+{}+{}",
                value_name(&self.light_points),
                value_name(&self.light_choice)
            );
        }
        s
    }

    /// Parse a preset name, `SAMPLER+DIRECTIONS+LIGHTS+POINTS+CHOICE`,
    /// `SAMPLER+DIRECTIONS+LIGHTS` (the light switches at their defaults), or
    /// `SAMPLER+DIRECTIONS` (lights `bsdf`, as before the light axis existed).
    pub fn parse(s: &str) -> Result<Strategy, String> {
        let s = s.trim();
        if let Ok(p) = Preset::from_str(s, false) {
            return Ok(p.strategy());
        }
        let parts: Vec<&str> = s.split('+').collect();
        if ![2, 3, 5].contains(&parts.len()) {
            return Err(format!(
                "unknown strategy '{s}': use a preset ({}) or SAMPLER+DIRECTIONS+LIGHTS \
                 (e.g. stratified+cosine+mis), with +POINTS+CHOICE for the light switches",
                value_names::<Preset>()
            ));
        }
        Ok(Strategy {
            sampler: parse_value(parts[0], "sampler")?,
            directions: parse_value(parts[1], "directions")?,
            lights: match parts.get(2) {
                Some(l) => parse_value(l, "lights")?,
                None => LightStrategy::Bsdf,
            },
            light_points: match parts.get(3) {
                Some(p) => parse_value(p, "light points")?,
                None => LightPoints::default(),
            },
            light_choice: match parts.get(4) {
                Some(c) => parse_value(c, "light choice")?,
                None => LightChoice::default(),
            },
        })
    }

    /// The strategy of a preset and single axes (the command line's `--strategy`,
    /// `--sampler`, `--directions`, `--lights`): an axis not given takes the preset's value, or
    /// the default's without a preset; an axis that contradicts the preset is an error.
    pub fn from_parts(
        preset: Option<Preset>,
        (sampler, directions, lights): (
            Option<SamplerKind>,
            Option<Directions>,
            Option<LightStrategy>,
        ),
        (points, choice): (Option<LightPoints>, Option<LightChoice>),
    ) -> Result<Strategy, String> {
        let with_light = |s: Strategy| Strategy {
            light_points: points.unwrap_or(s.light_points),
            light_choice: choice.unwrap_or(s.light_choice),
            ..s
        };
        let Some(preset) = preset else {
            let d = Strategy::default();
            return Ok(with_light(Strategy::of(
                sampler.unwrap_or(d.sampler),
                directions.unwrap_or(d.directions),
                lights.unwrap_or(d.lights),
            )));
        };
        let st = preset.strategy();
        let conflict = |flag: &str, uses: String, asked: String| {
            format!("--strategy {preset} uses --{flag} {uses}, not --{flag} {asked}")
        };
        if let Some(x) = sampler.filter(|&x| x != st.sampler) {
            return Err(conflict("sampler", st.sampler.to_string(), x.to_string()));
        }
        if let Some(x) = directions.filter(|&x| x != st.directions) {
            let uses = st.directions.to_string();
            return Err(conflict("directions", uses, x.to_string()));
        }
        if let Some(x) = lights.filter(|&x| x != st.lights) {
            return Err(conflict("lights", st.lights.to_string(), x.to_string()));
        }
        Ok(with_light(st))
    }

    /// A comma-separated list of strategies ([`Strategy::parse`] each), or `all`.
    pub fn parse_list(s: &str) -> Result<Vec<Strategy>, String> {
        if s.trim() == "all" {
            return Ok(Strategy::all());
        }
        s.split(',').map(Strategy::parse).collect()
    }

    /// What `--strategies` accepts, for help texts.
    pub fn list_help() -> String {
        format!(
            "Strategies, comma-separated: presets ({}), or SAMPLER+DIRECTIONS+LIGHTS with SAMPLER \
             one of {}, DIRECTIONS one of {} and LIGHTS one of {} (SAMPLER+DIRECTIONS means \
             +bsdf), optionally +POINTS+CHOICE with POINTS one of {} and CHOICE one of {} \
             (default {}+{}); `all` for every combination of the first three",
            value_names::<Preset>(),
            value_names::<SamplerKind>(),
            value_names::<Directions>(),
            value_names::<LightStrategy>(),
            value_names::<LightPoints>(),
            value_names::<LightChoice>(),
            value_name(&LightPoints::default()),
            value_name(&LightChoice::default())
        )
    }
}

impl std::fmt::Display for Strategy {
    /// The preset's name (`combined`), else `sampler+directions+lights`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.preset() {
            Some(p) => f.write_str(&value_name(&p)),
            None => f.write_str(&self.axes_name()),
        }
    }
}

/// The named points of the grid, in the mission's words.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Preset {
    /// independent points, uniform hemisphere directions: the naive baseline.
    Independent,
    /// stratified points, uniform hemisphere directions.
    Stratified,
    /// independent points, Phong-lobe importance sampling.
    Importance,
    /// stratified points, Phong-lobe importance sampling: the best without light sampling.
    Combined,
    /// stratified points, Phong-lobe directions, next-event estimation.
    Nee,
    /// stratified points, Phong-lobe directions, light and BSDF sampling under MIS: the
    /// default.
    Mis,
}

impl Preset {
    /// The point of the grid this preset names.
    pub fn strategy(self) -> Strategy {
        use LightStrategy as L;
        let (sampler, directions, lights) = match self {
            Preset::Independent => (SamplerKind::Independent, Directions::Uniform, L::Bsdf),
            Preset::Stratified => (SamplerKind::Stratified, Directions::Uniform, L::Bsdf),
            Preset::Importance => (SamplerKind::Independent, Directions::Phong, L::Bsdf),
            Preset::Combined => (SamplerKind::Stratified, Directions::Phong, L::Bsdf),
            Preset::Nee => (SamplerKind::Stratified, Directions::Phong, L::Nee),
            Preset::Mis => (SamplerKind::Stratified, Directions::Phong, L::Mis),
        };
        Strategy::of(sampler, directions, lights)
    }

    /// The mission's four presets (BSDF sampling only), in the order experiments report them.
    pub fn mission() -> Vec<Strategy> {
        [
            Preset::Independent,
            Preset::Stratified,
            Preset::Importance,
            Preset::Combined,
        ]
        .iter()
        .map(|p| p.strategy())
        .collect()
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&value_name(self))
    }
}

/// What `--strategy` names: a preset, or `auto` (a render that chooses among candidate
/// strategies by a pilot, [`crate::render::auto`]; `vrpt render` only).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StrategyName {
    /// A preset.
    Preset(Preset),
    /// Chosen per scene by a pilot.
    Auto,
}

impl StrategyName {
    const ALL: [StrategyName; 7] = [
        StrategyName::Preset(Preset::Independent),
        StrategyName::Preset(Preset::Stratified),
        StrategyName::Preset(Preset::Importance),
        StrategyName::Preset(Preset::Combined),
        StrategyName::Preset(Preset::Nee),
        StrategyName::Preset(Preset::Mis),
        StrategyName::Auto,
    ];
}

impl ValueEnum for StrategyName {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ALL
    }
    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        match self {
            StrategyName::Preset(p) => p.to_possible_value(),
            StrategyName::Auto => Some(clap::builder::PossibleValue::new("auto").help(
                "chosen per scene: a pilot renders each candidate (--auto-candidates), the most \
                 efficient by 1/(relMSE × cost) renders the image (vrpt render only)",
            )),
        }
    }
}

/// How points, directions and lights are sampled, as the flags give it: a preset, or the axes
/// separately (every command that renders takes these flags).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::Args)]
pub struct StrategyArgs {
    /// A named strategy; a --sampler, --directions or --lights given too must agree with it.
    #[arg(long, value_enum)]
    pub strategy: Option<StrategyName>,
    /// Where sample points come from (default: stratified).
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerKind>,
    /// How bounce directions are chosen (default: phong).
    #[arg(long, value_enum)]
    pub directions: Option<Directions>,
    /// How light is found at each vertex (default: mis).
    #[arg(long, value_enum)]
    pub lights: Option<LightStrategy>,
    /// How a point on a light is placed (default: auto).
    #[arg(long, value_enum)]
    pub light_points: Option<LightPoints>,
    /// How the light of a vertex is chosen (default: tree).
    #[arg(long, value_enum)]
    pub light_choice: Option<LightChoice>,
}

impl StrategyArgs {
    /// The strategy the flags ask for ([`Strategy::from_parts`]); an error if a flag
    /// contradicts the preset, or for `auto` (see [`StrategyArgs::is_auto`]).
    pub fn resolve(&self) -> Result<Strategy, String> {
        let preset = match self.strategy {
            Some(StrategyName::Auto) => {
                return Err(
                    "--strategy auto chooses the strategy by rendering: only vrpt \
                            render takes it"
                        .into(),
                )
            }
            Some(StrategyName::Preset(p)) => Some(p),
            None => None,
        };
        let axes = (self.sampler, self.directions, self.lights);
        Strategy::from_parts(preset, axes, (self.light_points, self.light_choice))
    }

    /// Whether the flags ask for `--strategy auto`; an error if they also set an axis (auto
    /// chooses whole strategies: name the candidates instead).
    pub fn is_auto(&self) -> Result<bool, String> {
        if self.strategy != Some(StrategyName::Auto) {
            return Ok(false);
        }
        let axes = [
            ("sampler", self.sampler.is_some()),
            ("directions", self.directions.is_some()),
            ("lights", self.lights.is_some()),
            ("light-points", self.light_points.is_some()),
            ("light-choice", self.light_choice.is_some()),
        ];
        match axes.iter().find(|(_, given)| *given) {
            Some((flag, _)) => Err(format!(
                "--strategy auto chooses whole strategies, not --{flag}: name the candidates \
                 with --auto-candidates"
            )),
            None => Ok(true),
        }
    }
}

impl From<Strategy> for StrategyArgs {
    /// Flags that give every axis of `s`.
    fn from(s: Strategy) -> Self {
        StrategyArgs {
            strategy: None,
            sampler: Some(s.sampler),
            directions: Some(s.directions),
            lights: Some(s.lights),
            light_points: Some(s.light_points),
            light_choice: Some(s.light_choice),
        }
    }
}

/// A comma-separated list of strategies as one flag value ([`Strategy::parse_list`]); a
/// newtype, so clap takes it as one value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Strategies(pub Vec<Strategy>);

impl Strategies {
    /// The list `s` names (a clap value parser).
    pub fn parse(s: &str) -> Result<Strategies, String> {
        Strategy::parse_list(s).map(Strategies)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        let all = Strategy::all();
        assert_eq!(
            all.len(),
            SamplerKind::value_variants().len()
                * Directions::value_variants().len()
                * LightStrategy::value_variants().len()
        );
        for s in &all {
            assert_eq!(Strategy::parse(&s.to_string()).unwrap(), *s);
            assert_eq!(Strategy::parse(&s.axes_name()).unwrap(), *s);
        }
        let name = |s: &str| Strategy::parse(s).unwrap().to_string();
        assert_eq!(name("combined"), "combined");
        assert_eq!(name("stratified+cosine"), "stratified+cosine+bsdf");
        assert_eq!(name("independent+phong"), "importance");
        assert_eq!(name("independent+phong+bsdf"), "importance");
        assert_eq!(name("stratified+phong+mis"), "mis");
        assert_eq!(name("independent+cosine+nee"), "independent+cosine+nee");
        assert!(Strategy::parse("nosuch+phong")
            .unwrap_err()
            .contains("sampler"));
        assert!(Strategy::parse("stratified+phong+x")
            .unwrap_err()
            .contains("lights"));
        assert!(Strategy::parse("a+b+c+d").is_err());
        assert!(Strategy::parse("best").is_err());
        let s = Strategy::parse("stratified+phong+mis+area+power").unwrap();
        assert_eq!(
            (s.light_points, s.light_choice),
            (LightPoints::Area, LightChoice::Power)
        );
        assert_eq!(s.to_string(), "stratified+phong+mis+area+power");
        assert_eq!(Strategy::parse(&s.to_string()).unwrap(), s);
        assert!(Strategy::parse("stratified+phong+mis+area").is_err());
        assert!(Strategy::parse("stratified+phong+mis+area+x")
            .unwrap_err()
            .contains("light choice"));
        assert_eq!(Preset::mission().len(), 4);
        assert_eq!(Strategy::default(), Preset::Mis.strategy());
    }
}
