//! `--strategy auto`: a render that chooses its own estimator from a pilot.
//!
//! Each candidate strategy renders a pilot of the same samples per pixel as
//! [`PILOT_REPLICATES`] independent replicates, with seeds of its own ([`pilot_seed`]) that no
//! other render uses. A pilot gives the image's relMSE, estimated from its replicates' spread
//! (honest for every sampler, [`crate::estimate`]), with a standard error from the spread of the
//! pixels' terms, and its cost. Its efficiency is `e = 1/(relMSE × cost)`: both factors scale
//! with the samples (relMSE as 1/spp, cost as spp), so pilots of any size compare.
//!
//! The cost is the wall time under a time limit (such a render is not deterministic anyway),
//! and otherwise the rays traced, training rays included: the same for every thread count, so
//! the choice, and the image, are too. Rays weigh a guided vertex's extra work (the guide's
//! lookup and sampling) as nothing, so a guided candidate looks slightly cheaper by rays than by
//! time.
//!
//! The rule, fixed before any pilot renders: the most efficient candidate is chosen if its
//! efficiency exceeds the first candidate's (the default) with `z = ln(e/e₀)/√(s² + s₀²) >`
//! [`SWITCH_Z`], `s = se(relMSE)/relMSE`; otherwise the first. The pilots' samples are
//! discarded, and the image is the chosen strategy's render with the render's own seed: the
//! same image as `--strategy CHOSEN`, so each choice is unbiased and so is their mixture.
//!
//! A pilot sees the budget of a pilot: a guide trained on 1/16 of the samples has learned less
//! than one trained on all of them, so the pilot understates guiding at large budgets.

use super::{render_passes, NoProgress, PassPlan, RenderSettings};
use crate::error::Result;
use crate::estimate::rel_mse_standard_error;
use crate::scene::Scene;
use crate::strategy::Strategy;
use std::time::{Duration, Instant};

/// Replicates of every pilot.
pub const PILOT_REPLICATES: u32 = 4;

/// The share of the budget (spp, or time) each candidate's pilot takes: 1/16.
pub const PILOT_SHARE: f64 = 1.0 / 16.0;

/// The z above which the most efficient candidate replaces the first: a false switch between
/// two equally efficient candidates has a one-sided normal probability of 2.3%, and the
/// standard errors are conservative ([`rel_mse_standard_error`]).
pub const SWITCH_Z: f64 = 2.0;

/// The candidates when none are named: today's default (stratified points, Phong directions,
/// MIS) and the same with guided directions.
pub fn default_candidates() -> Vec<Strategy> {
    let mis = Strategy::default();
    vec![
        mis,
        Strategy {
            directions: crate::bsdf::Directions::Guided,
            ..mis
        },
    ]
}

/// What a pilot's cost counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    /// Rays traced (camera, bounce, shadow; training included).
    Rays,
    /// Wall seconds.
    Seconds,
}

/// One candidate's pilot.
#[derive(Clone, Debug, PartialEq)]
pub struct PilotRow {
    /// The candidate.
    pub strategy: Strategy,
    /// Samples per pixel of the pilot (all replicates).
    pub spp: u32,
    /// The estimated relMSE ([`crate::estimate::ErrorEstimate`]).
    pub rel_mse: f64,
    /// Its standard error ([`rel_mse_standard_error`]).
    pub rel_mse_se: f64,
    /// Rays or seconds ([`Choice::cost`]).
    pub cost: f64,
    /// `1/(rel_mse × cost)`.
    pub efficiency: f64,
    /// Wall seconds of the pilot.
    pub seconds: f64,
}

/// What the pilots measured and which candidate they chose.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    /// The candidate chosen.
    pub strategy: Strategy,
    /// Its index among the candidates.
    pub index: usize,
    /// Every candidate's pilot, in the order given.
    pub rows: Vec<PilotRow>,
    /// What the costs count.
    pub cost: Cost,
    /// `z` of the most efficient candidate against the first (0 when it is the first).
    pub z: f64,
    /// Wall time of all the pilots.
    pub elapsed: Duration,
}

/// The seed of candidate `k`'s pilot in a render of seed `seed`: a hash no render's own seed
/// and no replicate seed of one meets but by a 64-bit collision.
pub fn pilot_seed(seed: u64, k: usize) -> u64 {
    // "pilot" in ASCII, as a domain separator
    crate::math::hash_words(&[0x70_69_6c_6f_74, seed, k as u64])
}

/// The pilot's samples per pixel for a render of `spp`: [`PILOT_SHARE`] of them, a multiple of
/// [`PILOT_REPLICATES`], at least one sample per replicate.
pub fn pilot_spp(spp: u32) -> u32 {
    let r = PILOT_REPLICATES;
    let share = (spp as f64 * PILOT_SHARE) as u32;
    (share / r * r).max(r)
}

/// The candidate the rule of the module doc chooses among `rows` (the first is the default),
/// and the `z` of the most efficient one against the first.
pub fn decide(rows: &[PilotRow]) -> (usize, f64) {
    let usable = |r: &PilotRow| r.efficiency.is_finite() && r.efficiency > 0.0;
    let Some(first) = rows.first().filter(|r| usable(r)) else {
        return (0, 0.0);
    };
    let best = (0..rows.len())
        .filter(|&k| usable(&rows[k]))
        .max_by(|&a, &b| rows[a].efficiency.total_cmp(&rows[b].efficiency))
        .unwrap_or(0);
    if best == 0 {
        return (0, 0.0);
    }
    let rel = |r: &PilotRow| r.rel_mse_se / r.rel_mse;
    let b = &rows[best];
    let z = (b.efficiency / first.efficiency).ln() / (rel(b).powi(2) + rel(first).powi(2)).sqrt();
    (if z > SWITCH_Z { best } else { 0 }, z)
}

/// Render a pilot of every candidate for a render of `settings` under `plan` and choose one
/// (see the module doc). Under a time limit the pilots' spp is what [`PILOT_SHARE`] of the time
/// allows at the first candidate's speed, measured on a pilot of [`PILOT_REPLICATES`] spp.
pub fn choose(
    scene: &Scene,
    settings: &RenderSettings,
    plan: &PassPlan,
    candidates: &[Strategy],
) -> Result<Choice> {
    let start = Instant::now();
    let cost = match plan.time_limit {
        Some(_) => Cost::Seconds,
        None => Cost::Rays,
    };
    let pilot = |k: usize, spp: u32| -> Result<PilotRow> {
        let s = RenderSettings {
            strategy: candidates[k],
            seed: pilot_seed(settings.seed, k),
            first_sample: 0,
            spp,
            replicates: PILOT_REPLICATES,
            ..settings.clone()
        };
        let p = PassPlan {
            stop: plan.stop.clone(),
            ..PassPlan::default()
        };
        let r = render_passes(scene, &s, &p, &NoProgress)?;
        let mean = r.film.mean_image();
        let e = &r.estimate;
        let se = rel_mse_standard_error(r.film.width, &mean, &e.variance);
        let rays = &r.stats.rays;
        let seconds = r.stats.elapsed.as_secs_f64();
        let spent = match cost {
            Cost::Rays => (rays.camera + rays.bounce + rays.shadow) as f64,
            Cost::Seconds => seconds,
        };
        Ok(PilotRow {
            strategy: candidates[k],
            spp: r.spp,
            rel_mse: e.rel_mse,
            rel_mse_se: se,
            cost: spent,
            efficiency: 1.0 / (e.rel_mse * spent),
            seconds,
        })
    };
    let mut rows = Vec::with_capacity(candidates.len());
    let spp = match plan.time_limit {
        None => pilot_spp(settings.spp),
        Some(limit) => {
            // the first candidate's speed, from a pilot of one sample per replicate
            let probe = pilot(0, PILOT_REPLICATES)?;
            let per_spp = probe.seconds / probe.spp as f64;
            let fits = limit.as_secs_f64() * PILOT_SHARE / per_spp.max(1e-12);
            let spp = pilot_spp(((fits / PILOT_SHARE) as u32).min(settings.spp));
            if spp == probe.spp {
                rows.push(probe);
            }
            spp
        }
    };
    for k in rows.len()..candidates.len() {
        rows.push(pilot(k, spp)?);
    }
    let (index, z) = decide(&rows);
    Ok(Choice {
        strategy: candidates[index],
        index,
        rows,
        cost,
        z,
        elapsed: start.elapsed(),
    })
}

impl Choice {
    /// The pilots as a table, and the choice, for the terminal.
    pub fn table(&self) -> String {
        let unit = match self.cost {
            Cost::Rays => "Mrays",
            Cost::Seconds => "seconds",
        };
        let scale = match self.cost {
            Cost::Rays => 1e-6,
            Cost::Seconds => 1.0,
        };
        let w = (self.rows.iter())
            .map(|r| r.strategy.to_string().len())
            .max()
            .unwrap_or(8)
            .max(8);
        let mut s = format!(
            "auto: pilots of {} spp ({} replicates) in {:.2} s\n  {:w$}  {:>10}  {:>9}  {:>9}  {:>10}\n",
            self.rows.first().map_or(0, |r| r.spp),
            PILOT_REPLICATES,
            self.elapsed.as_secs_f64(),
            "strategy",
            "relMSE",
            "± se",
            unit,
            "efficiency",
        );
        let e0 = self.rows.first().map_or(f64::NAN, |r| r.efficiency);
        for (k, r) in self.rows.iter().enumerate() {
            let mark = if k == self.index { " <- chosen" } else { "" };
            s += &format!(
                "  {:w$}  {:>10.3e}  {:>9.1e}  {:>9.3}  {:>10.2}{mark}\n",
                r.strategy.to_string(),
                r.rel_mse,
                r.rel_mse_se,
                r.cost * scale,
                r.efficiency / e0,
            );
        }
        s + &format!(
            "  efficiency relative to {}; the best against it: z = {:.1} (switch above {SWITCH_Z})\n",
            self.rows.first().map_or(String::new(), |r| r.strategy.to_string()),
            self.z
        )
    }

    /// One line for the metadata: the choice, each candidate's relative efficiency, z, the
    /// pilots' spp and cost.
    pub fn record(&self) -> String {
        let e0 = self.rows.first().map_or(f64::NAN, |r| r.efficiency);
        let rows: Vec<String> = (self.rows.iter())
            .map(|r| format!("{} {:.3}", r.strategy, r.efficiency / e0))
            .collect();
        format!(
            "chose {}; efficiency {}; z {:.2}; pilots {} spp, cost {}",
            self.strategy,
            rows.join(", "),
            self.z,
            self.rows.first().map_or(0, |r| r.spp),
            match self.cost {
                Cost::Rays => "rays",
                Cost::Seconds => "seconds",
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(strategy: Strategy, rel_mse: f64, se: f64, cost: f64) -> PilotRow {
        PilotRow {
            strategy,
            spp: 4,
            rel_mse,
            rel_mse_se: se,
            cost,
            efficiency: 1.0 / (rel_mse * cost),
            seconds: 0.1,
        }
    }

    #[test]
    fn the_rule_switches_only_past_the_noise() {
        let [a, b] = [default_candidates()[0], default_candidates()[1]];
        // b is twice as efficient, each relMSE known to 10%: z = ln 2 / (0.1·√2) = 4.9
        let (k, z) = decide(&[row(a, 0.02, 0.002, 100.0), row(b, 0.01, 0.001, 100.0)]);
        assert_eq!(k, 1);
        assert!((z - 2f64.ln() / (0.1 * 2f64.sqrt())).abs() < 1e-9, "{z}");
        // the same gain known only to 40%: z = 1.2, keep the first
        let (k, z) = decide(&[row(a, 0.02, 0.008, 100.0), row(b, 0.01, 0.004, 100.0)]);
        assert_eq!(k, 0);
        assert!(z > 1.0 && z < SWITCH_Z);
        // the first best: keep it; a candidate without an estimate is never chosen
        assert_eq!(
            decide(&[row(a, 0.01, 0.001, 1.0), row(b, 0.02, 0.001, 1.0)]).0,
            0
        );
        assert_eq!(
            decide(&[row(a, 0.01, 0.001, 1.0), row(b, f64::NAN, 0.0, 1.0)]).0,
            0
        );
        // cost counts as much as error: half the relMSE at three times the cost loses
        assert_eq!(
            decide(&[row(a, 0.02, 1e-4, 1.0), row(b, 0.01, 1e-4, 3.0)]).0,
            0
        );
    }

    #[test]
    fn pilots_take_a_sixteenth_in_whole_rounds_of_replicates() {
        assert_eq!(pilot_spp(1), 4);
        assert_eq!(pilot_spp(64), 4);
        assert_eq!(pilot_spp(256), 16);
        assert_eq!(pilot_spp(1000), 60);
        assert_ne!(pilot_seed(0, 0), pilot_seed(0, 1));
        assert_ne!(pilot_seed(0, 0), pilot_seed(1, 0));
    }
}
