//! `--strategy auto`'s candidates: what one is (a strategy, path reuse, roulette), how it is
//! named and parsed (`--auto-candidates`), and the default list.

use super::*;

/// One of `--strategy auto`'s candidates: a strategy, the side of its path-reuse blocks (1:
/// none; [`crate::integrator::reuse`]) and its roulette ([`Roulette`]). Named as the strategy
/// with `+reuseK` after it when `K > 1`, or `+ears` with efficiency-aware roulette and
/// splitting (the two do not combine: [`RenderSettings::roulette`]): `mis`, `mis+reuse4`,
/// `stratified+guided+mis+reuse2`, `mis+ears`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Candidate {
    /// The sampler, directions and lights.
    pub strategy: Strategy,
    /// Path reuse in blocks of `reuse × reuse` pixels ([`RenderSettings::reuse`]; 1: off).
    pub reuse: u32,
    /// Classic roulette, or EARS ([`RenderSettings::roulette`]).
    pub roulette: Roulette,
}

impl From<Strategy> for Candidate {
    fn from(strategy: Strategy) -> Candidate {
        Candidate {
            strategy,
            reuse: 1,
            roulette: Roulette::Classic,
        }
    }
}

impl std::fmt::Display for Candidate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.strategy)?;
        if self.reuse > 1 {
            write!(f, "+reuse{}", self.reuse)?;
        }
        if self.roulette == Roulette::Ears {
            f.write_str(EARS_SUFFIX)?;
        }
        Ok(())
    }
}

/// The suffix of a candidate with `--roulette ears`.
const EARS_SUFFIX: &str = "+ears";

impl Candidate {
    /// Parse a strategy ([`Strategy::parse`]), optionally with `+reuseK` or `+ears` after it.
    pub fn parse(s: &str) -> std::result::Result<Candidate, String> {
        let s = s.trim();
        let (rest, roulette) = match s.strip_suffix(EARS_SUFFIX) {
            Some(rest) => (rest, Roulette::Ears),
            None => (s, Roulette::Classic),
        };
        if roulette == Roulette::Classic && rest.contains(EARS_SUFFIX) {
            return Err(format!(
                "'{s}': +ears comes last, and does not combine with +reuseK (--roulette ears \
                 with --reuse)"
            ));
        }
        let Some((strategy, k)) = rest.rsplit_once("+reuse") else {
            let strategy = Strategy::parse(rest)?;
            return Ok(Candidate {
                roulette,
                ..Candidate::from(strategy)
            });
        };
        let reuse = (k.parse::<u32>().ok())
            .filter(|k| (1..=MAX_REUSE).contains(k))
            .ok_or_else(|| {
                format!("'{s}': +reuseK takes K from 1 (off) to {MAX_REUSE}, not '{k}'")
            })?;
        if reuse > 1 && roulette == Roulette::Ears {
            return Err(format!(
                "'{s}': +ears does not combine with +reuse{reuse} (--roulette ears with --reuse)"
            ));
        }
        Ok(Candidate {
            strategy: Strategy::parse(strategy)?,
            reuse,
            roulette,
        })
    }

    /// The same candidate with guided directions: its guided twin.
    pub fn guided(&self) -> Candidate {
        Candidate {
            strategy: Strategy {
                directions: Directions::Guided,
                ..self.strategy
            },
            ..*self
        }
    }

    /// The settings that render this candidate: `settings` with its strategy, reuse and
    /// roulette.
    pub fn settings(&self, settings: &RenderSettings) -> RenderSettings {
        RenderSettings {
            strategy: self.strategy,
            reuse: self.reuse,
            roulette: self.roulette,
            ..settings.clone()
        }
    }
}

/// A comma-separated list of candidates (`--auto-candidates`, a clap value parser).
#[derive(Clone, Debug, PartialEq)]
pub struct Candidates(pub Vec<Candidate>);

impl Candidates {
    /// The list `s` names ([`Candidate::parse`] each).
    pub fn parse(s: &str) -> std::result::Result<Candidates, String> {
        s.split(',')
            .map(Candidate::parse)
            .collect::<std::result::Result<_, _>>()
            .map(Candidates)
    }
}

/// The side of the reuse blocks of the default candidate with path reuse: at 10 s equal time
/// K = 4 gained 2.5–3.9× on the Cornell box, night-hall and the door, K = 3 1.8–2.9×
/// (`docs/reuse.md`).
pub const AUTO_REUSE: u32 = 4;

/// The candidates when none are named: today's default (stratified points, Phong directions,
/// MIS), the same with path reuse in blocks of [`AUTO_REUSE`]², and the guided twins of both
/// ([`Candidate::guided`]), staged (the module doc): where the light is caustic mis's twin
/// renders with its gate and no pilot, where path reuse beat mis the reusing twin
/// renders with its gate (on the rooms lit through a door or a slit, guiding and reuse together
/// gain 2× over reuse alone at 10 s), and elsewhere neither (where reuse does not win neither
/// does the guide, whose training would cost those renders a third of their time:
/// `docs/performance.md`).
pub fn default_candidates() -> Vec<Candidate> {
    let mis = Strategy::default();
    let reuse = Candidate {
        reuse: AUTO_REUSE,
        ..Candidate::from(mis)
    };
    let guided = Strategy {
        directions: Directions::Guided,
        ..mis
    };
    vec![
        Candidate::from(mis),
        reuse,
        Candidate::from(guided),
        Candidate {
            strategy: guided,
            ..reuse
        },
    ]
}
