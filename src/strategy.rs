//! The strategy: one point on the grid of variance-reduction axes, and its names.
//!
//! Each axis is an enum deriving `clap::ValueEnum` ([`SamplerKind`], [`Directions`]); every
//! name — flag values, `SAMPLER+DIRECTIONS` in experiments, metadata, the `all` list, help
//! text — comes from `ValueEnum::value_variants` and `to_possible_value`, so a new sampler or
//! direction strategy is one enum variant. The named presets of the mission ([`Preset`]) are
//! points on the grid: independent = (independent, uniform), stratified = (stratified, uniform),
//! importance = (independent, phong), combined = (stratified, phong).

use crate::bsdf::Directions;
use crate::sampler::SamplerKind;
use clap::ValueEnum;

/// The command-line name of a `ValueEnum` value.
pub fn value_name<T: ValueEnum>(v: &T) -> String {
    v.to_possible_value()
        .map_or_else(String::new, |p| p.get_name().to_string())
}

/// Parse a `ValueEnum` value by name, with an error that lists the valid names.
pub fn parse_value<T: ValueEnum>(s: &str, what: &str) -> Result<T, String> {
    T::from_str(s.trim(), false).map_err(|_| {
        format!(
            "unknown {what} '{}' (one of {})",
            s.trim(),
            value_names::<T>()
        )
    })
}

/// All names of a `ValueEnum`, comma-separated.
pub fn value_names<T: ValueEnum>() -> String {
    T::value_variants()
        .iter()
        .map(value_name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// How every random decision of a render is made: one value per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Strategy {
    /// Where the sample points come from.
    pub sampler: SamplerKind,
    /// How bounce directions are chosen.
    pub directions: Directions,
}

impl Default for Strategy {
    /// The best combination: stratified points, Phong-lobe directions.
    fn default() -> Self {
        Preset::Combined.strategy()
    }
}

impl Strategy {
    /// Every point of the grid, samplers outermost, in the enums' order.
    pub fn all() -> Vec<Strategy> {
        let mut v = Vec::new();
        for &sampler in SamplerKind::value_variants() {
            for &directions in Directions::value_variants() {
                v.push(Strategy {
                    sampler,
                    directions,
                });
            }
        }
        v
    }

    /// The preset that names this point, if any.
    pub fn preset(&self) -> Option<Preset> {
        Preset::value_variants()
            .iter()
            .copied()
            .find(|p| p.strategy() == *self)
    }

    /// `SAMPLER+DIRECTIONS`, whether or not a preset names it.
    pub fn axes_name(&self) -> String {
        format!(
            "{}+{}",
            value_name(&self.sampler),
            value_name(&self.directions)
        )
    }

    /// Parse a preset name or `SAMPLER+DIRECTIONS`.
    pub fn parse(s: &str) -> Result<Strategy, String> {
        let s = s.trim();
        if let Ok(p) = Preset::from_str(s, false) {
            return Ok(p.strategy());
        }
        let Some((a, b)) = s.split_once('+') else {
            return Err(format!(
                "unknown strategy '{s}': use a preset ({}) or SAMPLER+DIRECTIONS (e.g. stratified+cosine)",
                value_names::<Preset>()
            ));
        };
        Ok(Strategy {
            sampler: parse_value(a, "sampler")?,
            directions: parse_value(b, "directions")?,
        })
    }

    /// What `--strategies` accepts, for help texts.
    pub fn list_help() -> String {
        format!(
            "presets ({}), or SAMPLER+DIRECTIONS with SAMPLER one of {} and DIRECTIONS one of {}; \
             `all` for every combination",
            value_names::<Preset>(),
            value_names::<SamplerKind>(),
            value_names::<Directions>()
        )
    }
}

impl std::fmt::Display for Strategy {
    /// The preset's name (`combined`), else `sampler+directions` (`stratified+cosine`).
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
    /// stratified points, Phong-lobe importance sampling: the best combination.
    Combined,
}

impl Preset {
    /// The point of the grid this preset names.
    pub fn strategy(self) -> Strategy {
        let (sampler, directions) = match self {
            Preset::Independent => (SamplerKind::Independent, Directions::Uniform),
            Preset::Stratified => (SamplerKind::Stratified, Directions::Uniform),
            Preset::Importance => (SamplerKind::Independent, Directions::Phong),
            Preset::Combined => (SamplerKind::Stratified, Directions::Phong),
        };
        Strategy {
            sampler,
            directions,
        }
    }

    /// Every preset's strategy, in the order experiments report them.
    pub fn all() -> Vec<Strategy> {
        Preset::value_variants()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        let all = Strategy::all();
        assert_eq!(
            all.len(),
            SamplerKind::value_variants().len() * Directions::value_variants().len()
        );
        for s in &all {
            assert_eq!(Strategy::parse(&s.to_string()).unwrap(), *s);
            assert_eq!(Strategy::parse(&s.axes_name()).unwrap(), *s);
        }
        assert_eq!(Strategy::parse("combined").unwrap().to_string(), "combined");
        assert_eq!(
            Strategy::parse("stratified+cosine").unwrap().to_string(),
            "stratified+cosine"
        );
        assert_eq!(
            Strategy::parse("independent+phong").unwrap().to_string(),
            "importance"
        );
        assert!(Strategy::parse("nosuch+phong")
            .unwrap_err()
            .contains("sampler"));
        assert!(Strategy::parse("best").is_err());
        assert_eq!(Preset::all().len(), 4);
        assert_eq!(Strategy::default(), Preset::Combined.strategy());
    }
}
