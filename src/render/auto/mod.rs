//! `--strategy auto`: a render that chooses its own estimator from a pilot.
//!
//! A candidate ([`Candidate`]) is a strategy with path reuse in blocks of `K × K` pixels or
//! without, or with efficiency-aware roulette and splitting (`mis`, `mis+reuse4`, `mis+ears`).
//! Each candidate renders a pilot of the same samples per pixel as [`PILOT_REPLICATES`]
//! independent replicates, with seeds that no other render uses ([`pilot_seed`]) and that every
//! candidate's pilot shares (common random numbers: path reuse traces the very paths of the
//! strategy without it, so where the light comes by rare paths, both pilots find the same ones
//! or miss them together, and their ratio does not hang on which pilot was lucky), on
//! the same spread quarter (or half) of the image's tiles ([`pilot_strip`]: a pilot costs a
//! quarter of what the whole image would, and the choice is made from the same tiles for
//! every candidate). A pilot gives the pilot's relMSE, estimated from its replicates' spread
//! (honest for every sampler, [`crate::estimate`]) against one denominator `r² + 0.01` shared by
//! every candidate (`r²` estimated from the pilots' images pooled by inverse variance, which
//! weighs the least noisy most: with equal weights, at two samples per replicate, the door's
//! pilots read path reuse 2.8× better per sample where it is 8–9×), with a standard
//! error from the spread of the pixels' terms, and its cost. Each pilot's own image as the
//! denominator, as a render's estimate takes it, fails a pilot: at a pilot's few samples a
//! pixel's mean is mostly noise, so its relMSE saturates near one whatever the estimator (the
//! gap's mis render at 16, 64 and 256 spp estimates 0.18, 0.20 and 0.17, its MSE falling as
//! 1/N), and where one pilot met a rare bright path its own bright mean hides it: the gap's
//! pilots read path reuse 0.65× as efficient as mis so, and 1.12× against the shared
//! denominator (it is 2.1× at 10 s). Its efficiency is `e = 1/(relMSE × cost)`: both factors scale
//! with the samples (relMSE as 1/spp, cost as spp), so pilots of any size compare. Path reuse
//! correlates neighbouring pixels' errors; each pixel's variance is still estimated honestly by
//! its replicates, but the standard error, which counts the pixels' terms as independent, is
//! then somewhat low (the squares of errors correlated by ρ ≈ 0.3 between neighbours correlate
//! by about ρ² ≈ 0.1).
//!
//! The cost is the wall time under a time limit (such a render is not deterministic anyway),
//! and otherwise a count of work: the rays traced (an EARS candidate's training in its pilot
//! included; a guided candidate's guide training not, as a cost sunk before its pilot that the
//! render chosen does not pay again), with each shadow ray
//! of a reuse connection weighed [`CONNECTION_COST`] (it is a shadow ray and two BSDF
//! evaluations, no surface to shade; see the constant for the measurement) and each ray of an
//! EARS candidate weighed [`EARS_RAY_COST`] (its cache lookups and recursion). A count is the same
//! for every thread count, so the choice, and the image, are too; a guided candidate's rays
//! weigh [`GUIDED_RAY_COST`] (the guide's lookups and descents). Under a time limit the pilots'
//! wall time is noisy (a tenth of a second on a strip, on a shared machine: textured's reuse pilot once took 1.14× the mis
//! pilot's time, and 1.5–1.9× in three other renders, which switched the choice there), but
//! rays miss what a ray costs in each scene: counted in rays at 10 s the door's pilots read
//! reuse 1.06× as efficient (z 2.2–2.4), by time 1.14–1.24× (z 5–9; it wins 4× there), and
//! textured's read it 1.10–1.18× in every render (it loses 2× there at 10 s).
//!
//! The rule, fixed before any pilot renders: the most efficient candidate is chosen if its
//! efficiency exceeds the first candidate's (the default) with `z = ln(e/e₀)/√(s² + s₀²) >`
//! [`SWITCH_Z`], `s = se(relMSE)/relMSE`; otherwise the first. (The noise of the pilots' wall
//! times is not in `z`: counted at its measured 12% per pilot, it kept mis in one of four renders
//! of the door and door-dark, where reuse wins 3–4×, and the geometric mean of the equal-time
//! gain over mis fell from 1.48× to 1.29×; see `docs/performance.md`.) The pilots' samples are
//! discarded, and the image is the chosen candidate's render with the render's own seed: the
//! same image as `--strategy CHOSEN [--reuse K | --roulette ears]` (but for a guided candidate's
//! guide, below), so each choice is unbiased and so is their mixture.
//!
//! **Early pilots.** The pilots render first at a quarter of their spp ([`early_spp`]); where
//! these decide beyond doubt ([`EARLY_Z`], [`EARLY_RATIO`], fixed before any pilot renders) the
//! full pilots do not render, else they do and the early ones are discarded: at 10 s on the
//! scenes lit indirectly the pilots took 0.07–0.19 s where the full ones took 0.35–0.50 s, and
//! chose alike (`docs/performance.md`).
//!
//! A guided candidate (`stratified+guided+mis`) first learns its guide on the pilots' strip,
//! with its training's own seeds and a budget of [`GUIDE_SHARE`] of the render's (as many
//! samples per pixel of the strip as a guided render's own training takes per pixel of the
//! image), and its pilot samples with that guide; if it is chosen, the render samples with
//! the same guide and does not train ([`PassPlan::guide`]): nothing the pilot learned is
//! thrown away, and the pilot measured the guide the image is rendered with. Its image is then
//! not `--directions guided`'s (whose guide trains on the whole image), but unbiased for the
//! same reason: the guide and the choice come from samples independent of the image's.
//!
//! The image's edge map ([`super::edges`]: which pixels see an edge of a light, and their edge
//! rays) is found once, with the render's seed and the first candidate's integrator, before
//! the pilots: every pilot renders with it, and the render chosen does too where it is the
//! map that render would find itself (the same bits: `EdgeMap::fits`). It depends on
//! neither the pilots' samples nor the render's, so the choice and the image stay unbiased;
//! found by each pilot and again by the render, it took ~10 ms of a 0.1-s render apiece. Its
//! rays are in no pilot's cost (each pilot counted them before, some 5 rays a pixel of the
//! image added to every candidate's cost in rays, as much as a pilot's own rays at 64 spp:
//! the efficiency ratios were drawn toward one, the dearer candidates favoured).
//!
//! Path reuse shares the paths' second vertices between the pixels of a block, so it lowers
//! the variance of the light found from the second vertex on and of nothing else
//! ([`crate::integrator::RayCounts::indirect`]). Where less than [`INDIRECT_GATE`] of the first
//! candidate's light was indirect in the probe, no candidate with path reuse is piloted: on the
//! scenes lit directly such a pilot, 3–4× a mis pilot's cost, was most of what auto paid for
//! its choice of mis.
//!
//! The gates (this one and [`CAUSTIC_GATE`], below) read a probe: the first candidate rendered
//! on the pilots' strip with the pilots' seed at [`PROBE_SPP`] (under a time limit the probe
//! that measures the speed, [`PILOT_REPLICATES`] samples). Where they leave no candidate but
//! the first to pilot (the default candidates on a scene lit directly), no pilot renders and the
//! first is chosen: its own pilot would have measured nothing a choice needs. There mis's pilot,
//! 4 spp as four 1-spp replicate passes, was the rest of what auto paid (30–50 ms of
//! checker-plane's 0.3-s render; the probe is a quarter of its samples in one pass). The gate
//! read by a probe of one sample per pixel is as sharp as by a pilot's four: over seeds 1–8 at
//! each scene's own size, the probe's indirect share reads 23–24% on the Cornell box, 45–49% in
//! the night hall, 5–6% on sun-sky, 7–8% on textured, 0 on the glossy plates; the glass scene's
//! caustic share 6–8%.
//!
//! Guided candidates (but a guided first one) are staged ([`GuidedStage`]): the unguided
//! candidates are piloted first, and the guided ones come in only where an unguided candidate
//! other than the first beat it beyond the noise, where at least [`CAUSTIC_GATE`] of the first
//! candidate's light came as caustics in the probe (through a mirror or glass after a Phong vertex:
//! light only a bounce finds, which a guide learns to aim at), or where the list names no
//! unguided one but the first (then they are piloted with the rest). Where they come in, the
//! one considered is a *guided twin* ([`Candidate::guided`]: the same but for guided
//! directions) where the list holds it, else every guided one:
//!
//! - **The twin rendered, not piloted.** Where the list holds the guided twin of the unguided
//!   pilots' choice, the twin is chosen without a pilot and renders as `--directions guided`
//!   does: its own guide trained over the whole image, and the guide's gate ([`super::gate`]),
//!   which compares it with Phong directions during the training and renders the rest with
//!   them where the guide loses. A pilot's guide, trained on a quarter of the tiles with an
//!   eighth of the time, is poorer than a guided render's own, and its training and pilot took
//!   10–17% of a 10-s render: at 10 s (three seed pairs, interleaved) the twin rendered
//!   lowered auto's relMSE 1.29× on the door, 1.16× on door-dark and 1.08× on the gap against
//!   the twin piloted with a handed guide, reaching 0.97–1.04× of `--directions guided --reuse
//!   4`; on the Cornell box (guiding adds nothing) 0.97×; in the night hall, where the guide
//!   loses 1.2× by its gate's first reading, 0.96× (with its gate closing at that reading: see
//!   [`super::gate::GATE_Z_ALONE`]; 0.82× when it waited for a second). The twin renders only
//!   where its training reaches its gate's first reading, else the unguided choice does
//!   ([`GuidedStage::Unread`], `stage.rs`): at the night hall's default 16 spp the twin rendered
//!   guided without a reading and auto reached 0.67× the efficiency of `--reuse 4`; with
//!   the rule it renders `--reuse 4`'s image.
//! - **Caustics: the first candidate's twin, no pilot.** Next-event estimation
//!   never reaches a caustic; a guide is what finds it. Path reuse shares the light samples'
//!   connections between pixels, and a caustic comes by no connection: with guided directions
//!   it cost the lamp 1.08× and the glass scene 1.33× in relMSE at 10 s. So where the probe
//!   finds caustics and the first candidate's twin is listed, no candidate is piloted.
//!   The gate, not a pilot, guards the choice, so [`CAUSTIC_GATE`] is low: any scene with a
//!   mirror or glass in the light's way.
//! - Where the twin is not listed, every guided candidate is piloted after the unguided ones:
//!   a guided candidate's pilot first learns its guide on the pilots' strip (below), and the
//!   render chosen samples with it.
//!
//! Where they do not come in (direct light, glossy reflections) a guided pilot read no better
//! and its training cost those renders 8–19% of their samples (the glossy plates: 229 spp at 10 s
//! against mis's 276). The rule is fixed before any pilot renders, and the choice is still made
//! from the pilots alone (the gate of a rendered twin from its own training, as any guided
//! render's). A guided candidate's pilot does not see the light that comes by rare paths better
//! than the others' (on the gap, door-dark and the glass scene at 10 s the guided pilot without
//! reuse read 0.35–1.16× the efficiency of mis, where guided renders win 1.5–4.2× over mis), so
//! guided directions alone are a default candidate only as mis's twin. Path reuse learns
//! nothing, so a pilot sees what the render will get; EARS learns its factors from its pilot's
//! own training, shorter than a render's, and is not a default candidate either (where it wins,
//! `mis+reuse4` wins more: `docs/roulette.md`).

use super::edges::EdgeMap;
use super::{LearnedGuide, PassPlan, RenderSettings, TileStrip, TrainingBudget};
use crate::bsdf::Directions;
use crate::error::Result;
use crate::integrator::reuse::MAX_REUSE;
use crate::integrator::rrs::Roulette;
use crate::scene::Scene;
use crate::strategy::Strategy;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Replicates of every pilot.
pub const PILOT_REPLICATES: u32 = 4;

/// The samples per pixel of the probe (one replicate) that renders the first candidate on the
/// pilots' strip before any pilot: the gates read its light's shares ([`INDIRECT_GATE`],
/// [`CAUSTIC_GATE`]), and where they leave no candidate but the first to pilot, it is chosen
/// without a pilot. (Under a time limit the probe is [`PILOT_REPLICATES`] samples, one per
/// replicate: it measures the speed too.)
pub const PROBE_SPP: u32 = 1;

/// The share of the first candidate's light found from the second vertex on in the probe
/// ([`crate::integrator::RayCounts::indirect_share`], [`PROBE_SPP`]) below which no candidate
/// with path reuse is piloted (the module doc). Path reuse shares the paths' second vertices
/// between pixels, so it can lower only the variance of the light found from there on; where
/// that light is a small part of the image, its pilot (the dearest: 3–4× a mis pilot's time)
/// buys nothing.
/// Measured with `vrpt render SCENE --spp 16 --stats` (the share is printed with the rays): the
/// five scenes lit directly 0–7% (checker-plane and lit-checker 0, the glossy plates 0.3%,
/// sun-sky 4.7%, textured 7.2%), where path reuse gains at most 1.07× over mis at 10 s and
/// loses up to 2×; the others 26–100% (the Cornell box 26%, glass 34%, the night hall 46%, the
/// gap 81%, door-dark 87%, the door 89%, the lamp 100%), where it gains 2.7–4× (but on glass
/// and the lamp, whose caustics it does not reach). 15% is twice the highest of the first and
/// half the lowest of the second.
pub const INDIRECT_GATE: f64 = 0.15;

/// The share of the budget's spp each candidate's pilot takes: 1/16 (on its strip of tiles, so
/// 1/64 of the render's cost where the strip is a quarter of the image).
pub const PILOT_SHARE: f64 = 1.0 / 16.0;

/// The fewest whole tiles a pilot's strip holds ([`pilot_strip`]): 12 tiles are 3072 pixels.
pub const PILOT_TILES: usize = 12;

/// The z above which the most efficient candidate replaces the first: a false switch between
/// two equally efficient candidates has a one-sided normal probability of 2.3%, and the
/// standard errors are conservative ([`crate::estimate::rel_mse_against`]).
pub const SWITCH_Z: f64 = 2.0;

/// What one shadow ray of a reuse connection costs, in rays of the rest of the render (each
/// of which carries its share of shading, light sampling and film). Measured on one thread,
/// 128×96 at 32 spp, the extra time of `--reuse K` over its extra shadow rays against the time
/// per ray without reuse, K = 2, 3, 4: Cornell box 0.93, 0.80, 0.67; door 0.69, 0.61, 0.58;
/// textured 1.12, 0.75, 0.62; night-hall 0.37, 0.26, 0.25 (its rays are long and its shading
/// dear): the blocks' bookkeeping is shared by more connections at larger K. At K = 4 the
/// weight 0.6 puts a render's cost within −5% to +2% of its time on the first three and +51%
/// on night-hall, where it overstates what reuse costs (a switch it makes is then safe).
pub const CONNECTION_COST: f64 = 0.6;

/// What one ray of an EARS candidate (`+ears`) costs, in rays of the same strategy with classic
/// roulette: its cache lookup at each vertex, the recursion of its continuations and their
/// bookkeeping, the training's records. Measured on one thread, 128×96 at 32 spp (training
/// included), time per ray with EARS over time per ray without, three runs each: Cornell box
/// 1.34, door 1.24, glossy plates 1.17, night-hall 1.23; with 1.25 a pilot's cost is within
/// about ±7% of its time on all four.
pub const EARS_RAY_COST: f64 = 1.25;

/// What one ray of a guided candidate costs, in rays of the same strategy with Phong
/// directions: the S-tree lookup and the quadtree descents at each vertex. Measured on one
/// thread, 128×96 at 32 spp, time per ray of a render given its guide (a guided candidate's
/// render: no training, no records) over `--strategy mis`, two runs each: Cornell box 1.49,
/// 1.18; door 1.98, 1.56; glossy plates 1.36, 1.49; gap 1.84, 1.36; the median 1.49. (With the
/// training, as `--directions guided` renders, 1.7–2.2.)
pub const GUIDED_RAY_COST: f64 = 1.5;

/// What a pilot's cost counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    /// Rays traced (camera, bounce, shadow; an EARS pilot's training included, a guided
    /// candidate's guide training not), a reuse connection's shadow ray weighed
    /// [`CONNECTION_COST`], every ray of an EARS candidate [`EARS_RAY_COST`], of a guided one
    /// [`GUIDED_RAY_COST`].
    Rays,
    /// Wall seconds.
    Seconds,
}

/// One candidate's pilot.
#[derive(Clone, Debug, PartialEq)]
pub struct PilotRow {
    /// The candidate.
    pub candidate: Candidate,
    /// Samples per pixel of the pilot (all replicates).
    pub spp: u32,
    /// The relMSE estimated from its replicates, against the denominator every pilot shares
    /// (the module doc).
    pub rel_mse: f64,
    /// Its standard error ([`crate::estimate::rel_mse_against`]).
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
    pub candidate: Candidate,
    /// The first candidate (the default: the probe's, and the one the others must beat).
    pub first: Candidate,
    /// Its row (with [`GuidedStage::Rendered`], its unguided twin's: the chosen one has none).
    pub index: usize,
    /// The candidates' pilots: the unguided candidates' in the order given, then the guided
    /// ones' (but a guided first candidate's, which comes first) when they were piloted.
    pub rows: Vec<PilotRow>,
    /// The candidates neither piloted nor rendered ([`Choice::stage`] says why).
    pub unpiloted: Vec<Candidate>,
    /// Whether the guided candidates were piloted, rendered without a pilot or neither.
    pub stage: GuidedStage,
    /// What the costs count.
    pub cost: Cost,
    /// `z` of the most efficient candidate against the first (0 when it is the first).
    pub z: f64,
    /// The share of the first candidate's light that was caustic in the probe
    /// ([`crate::integrator::RayCounts::caustic_share`]; see [`CAUSTIC_GATE`]).
    pub caustic: f64,
    /// The share of the first candidate's light found from the second vertex on in the probe
    /// ([`crate::integrator::RayCounts::indirect_share`]; see [`INDIRECT_GATE`]).
    pub indirect: f64,
    /// The probe's samples per pixel ([`PROBE_SPP`]; under a time limit [`PILOT_REPLICATES`],
    /// one per replicate).
    pub probe: u32,
    /// The full pilots' samples per pixel; the rows' are [`early_spp`] of it where the early
    /// pilots decided ([`EARLY_Z`]).
    pub planned: u32,
    /// Wall time of the probe and all the pilots.
    pub elapsed: Duration,
    /// The tiles the probe and the pilots rendered, and the image's (partial ones included).
    pub tiles: (u32, u32),
    /// The guide the chosen candidate's pilot learned, when its directions are guided: the
    /// render samples with it ([`PassPlan::guide`]).
    pub guide: Option<Arc<LearnedGuide>>,
    /// The image's edge map the pilots rendered with, when it is the one the chosen
    /// candidate's render would find itself ([`PassPlan::edges`]).
    pub edges: Option<Arc<EdgeMap>>,
}

/// The share of the first candidate's light in the probe that came as caustics (through a
/// mirror or glass after a Phong vertex: [`crate::integrator::RayCounts::caustic_share`]) at or
/// above which the guided candidates come in even where no unguided candidate beat the first,
/// the first's guided twin rendered with its gate and no pilot where the list holds it (the
/// module doc). Caustics are light no light sample reaches, which only a bounce aimed at
/// the mirror or glass finds, and path reuse does not help there; a guide learns to aim.
/// Measured with `vrpt render SCENE --spp 16` (the share is printed with the rays): the lamp
/// behind its glass shade 54% (the rest is the lamp seen through the shade from the camera, not
/// a caustic), the glass scene 9%, every other shipped scene 0 (no mirror or glass); auto's mis
/// pilots read the lamp 99% and the glass scene 6–7% (seeds 1–3, 10 s). Guided directions gain
/// 1.9× over mis at 10 s on the lamp and 1.9× on the glass scene; auto, before the twin was
/// rendered, reached 0.59–0.65× of the best there. A share of 1/50 admits both: where a guide
/// then learns nothing, its gate closes and the render pays its training up to the probe (the
/// glossy plates: 0.97× of Phong directions at 10 s).
pub const CAUSTIC_GATE: f64 = 0.02;

/// The share of the render's budget a guided candidate's guide trains on, before its pilot: its
/// training iterations ([`crate::guiding`]) on the pilots' strip take at most this share of the
/// time limit, and of the render's samples (`spp × GUIDE_SHARE / strip share` samples per pixel
/// of the strip, so about this share of the render's cost). On a strip of a quarter of the
/// image that is `spp/2` samples per pixel of it, the `spp/2` a guided render's own training
/// takes per pixel of the image (under a time limit `T/8` on a quarter of the pixels, about the
/// `T/2` of a whole image, against its `T/3`); the render chosen samples with this guide and
/// trains no more. Measured at 10 s (auto with the default candidates, three seed pairs, the
/// three shares interleaved), relMSE at 1/16, 1/8 and 1/4: door-dark 5.60e-3, 4.14e-3, 3.89e-3;
/// the gap 0.231, 0.216, 0.244; the door 0.0400, 0.0387, 0.0316; the Cornell box (where guiding
/// adds nothing) 1.228e-3, 1.227e-3, 1.399e-3. 1/8 gains or ties on all four; 1/4 loses on two.
pub const GUIDE_SHARE: f64 = 1.0 / 8.0;

/// The training budget of a guided candidate's guide for a render of `spp` under `time_limit`,
/// trained on a strip of `share` of the image's pixels ([`GUIDE_SHARE`]).
pub fn guide_budget(spp: u32, share: f64, time_limit: Option<Duration>) -> TrainingBudget {
    TrainingBudget {
        spp: ((spp as f64 * GUIDE_SHARE / share.clamp(1e-6, 1.0)) as u64).max(1),
        time: time_limit.map(|t| t.mul_f64(GUIDE_SHARE)),
    }
}

/// The seed of every candidate's pilot in a render of seed `seed` (common random numbers: see
/// the module doc): a hash no render's own seed and no replicate seed of one meets but by a
/// 64-bit collision.
pub fn pilot_seed(seed: u64) -> u64 {
    // "pilot" in ASCII, as a domain separator
    crate::math::hash_words(&[0x70_69_6c_6f_74, seed, 0])
}

/// The tiles the pilots of a `width × height` render take: a quarter of the whole tiles
/// ([`TileStrip::every`], stride 4) where that is at least [`PILOT_TILES`], else half where
/// that is; `None` (the whole image) for a smaller image.
pub fn pilot_strip(width: u32, height: u32) -> Option<TileStrip> {
    [4, 2]
        .into_iter()
        .map(|stride| TileStrip::every(width, height, stride))
        .find(|s| s.origins.len() >= PILOT_TILES)
}

/// The pilot's samples per pixel for a render of `spp`: [`PILOT_SHARE`] of them, a multiple of
/// [`PILOT_REPLICATES`], at least one sample per replicate.
pub fn pilot_spp(spp: u32) -> u32 {
    let r = PILOT_REPLICATES;
    let share = (spp as f64 * PILOT_SHARE) as u32;
    (share / r * r).max(r)
}

/// The z beyond which pilots of a quarter of the spp ([`early_spp`]) decide, where the most
/// efficient candidate is also at least [`EARLY_RATIO`] times as efficient as the first: then
/// the full pilots do not render. The relMSE's standard error shrinks slowly with the pilots'
/// spp (each pixel's variance comes from [`PILOT_REPLICATES`] replicates at any spp: at 10 s
/// the early pilots' z was 0.5–0.95 of the full ones' with a third to a tenth of the samples),
/// but a pilot of a few samples a pixel misses rare paths and its wall time is noisier; the
/// full pilots stay for every choice that is not clear.
pub const EARLY_Z: f64 = 6.0;

/// The least efficiency ratio, best over first, at which early pilots decide ([`EARLY_Z`]):
/// the pilots' wall times, the cost under a time limit, vary by about 12% a pilot and more for
/// a shorter one, and are not in `z`; a ratio of 1.5 is beyond what that noise makes.
pub const EARLY_RATIO: f64 = 1.5;

/// The early pilots' spp for pilots of `spp`: a quarter, in whole rounds of replicates (≥ 1).
pub fn early_spp(spp: u32) -> u32 {
    let r = PILOT_REPLICATES;
    (spp / 4 / r * r).max(r)
}

/// Whether early pilots' `rows` decide beyond doubt: the rule ([`decide`]) switches from the
/// first with `z >` [`EARLY_Z`] to a candidate at least [`EARLY_RATIO`] as efficient.
fn decided_early(rows: &[PilotRow]) -> bool {
    let (best, z) = decide(rows);
    best != 0 && z > EARLY_Z && rows[best].efficiency >= EARLY_RATIO * rows[0].efficiency
}

/// The staged pilots ([`pilot_staged`]) at [`early_spp`] of `spp` where they pilot nothing or
/// decide beyond doubt ([`decided_early`]), else those at `spp`.
fn pilot_early_then_full(
    pilots: &mut Pilots,
    candidates: &[Candidate],
    spp: u32,
    gates: Gates,
) -> Result<(Vec<usize>, Vec<pilot::Pilot>, GuidedStage)> {
    let early = early_spp(spp);
    if early < spp {
        let staged = pilot_staged(pilots, candidates, early, gates)?;
        if staged.1.is_empty() || decided_early(&shared_denominator(pilots.width, &staged.1)) {
            return Ok(staged);
        }
    }
    pilot_staged(pilots, candidates, spp, gates)
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
    candidates: &[Candidate],
) -> Result<Choice> {
    if candidates.is_empty() {
        return Err(crate::error::Error::Settings("auto: no candidates".into()));
    }
    let start = Instant::now();
    let cost = match plan.time_limit {
        Some(_) => Cost::Seconds,
        None => Cost::Rays,
    };
    let mut pilots = Pilots::new(scene, settings, plan, candidates, cost)?;
    // the probe: the first candidate's light shares, which the gates read, and under a time
    // limit its speed. The probe is not the first candidate's pilot even when the spp comes
    // out the same: it is the first render of the process on these tiles and pays for the
    // threads, caches and pages it warms (glass, 4-spp pilots: the probe taken as mis's pilot
    // read its time 1.02× reuse 4's, which takes 1.79× mis's time at 10 s, and auto chose
    // reuse, z 9.5)
    let probe = match plan.time_limit {
        None => pilots.run_as(0, PROBE_SPP, 1)?,
        Some(_) => pilots.run(0, PILOT_REPLICATES)?,
    };
    let spp = match plan.time_limit {
        None => pilot_spp(settings.spp),
        Some(limit) => {
            // the spp the image would take at the probe's speed in the time limit
            let per_spp = probe.seconds / probe.spp as f64 / pilots.share;
            let fits = limit.as_secs_f64() / per_spp.max(1e-12);
            pilot_spp((fits as u32).min(settings.spp))
        }
    };
    let gates = Gates {
        caustic: probe.caustic >= CAUSTIC_GATE,
        direct: probe.indirect < INDIRECT_GATE,
        per_spp: (plan.time_limit).map(|_| probe.seconds / probe.spp as f64 / pilots.share),
        start,
    };
    let (ks, done, stage) = pilot_early_then_full(&mut pilots, candidates, spp, gates)?;
    let rows = shared_denominator(pilots.width, &done);
    let (index, z) = decide(&rows);
    // the first candidate where none was piloted
    let k = ks.get(index).copied().unwrap_or(0);
    let candidate = match stage {
        GuidedStage::Rendered => candidates[k].guided(),
        _ => candidates[k],
    };
    let chosen = candidate.settings(settings);
    let edges = (pilots.edges.clone()).filter(|m| super::edges::edges_fit(m, &chosen, plan));
    Ok(Choice {
        candidate,
        first: candidates[0],
        index,
        rows,
        unpiloted: (0..candidates.len())
            .filter(|&j| !ks.contains(&j) && candidates[j] != candidate)
            .map(|j| candidates[j])
            .collect(),
        stage,
        cost,
        z,
        caustic: probe.caustic,
        indirect: probe.indirect,
        probe: probe.spp,
        planned: spp,
        elapsed: start.elapsed(),
        tiles: pilots.tiles,
        guide: match stage {
            GuidedStage::Rendered => None,
            _ => pilots.guides[k].take(),
        },
        edges,
    })
}

impl Choice {
    /// The settings of the render after the pilots: `settings` with the chosen candidate's
    /// strategy, reuse and roulette.
    pub fn settings(&self, settings: &RenderSettings) -> RenderSettings {
        self.candidate.settings(settings)
    }

    /// The plan of the render after the pilots: `plan` with the time the pilots did not use,
    /// and the chosen candidate's guide when it learned one; a guided twin rendered where the
    /// probe found no caustics takes its gate's early look ([`PassPlan::gate_early`]).
    pub fn plan(&self, plan: &PassPlan) -> PassPlan {
        PassPlan {
            time_limit: (plan.time_limit).map(|t| t.saturating_sub(self.elapsed)),
            guide: self.guide.clone(),
            edges: self.edges.clone(),
            gate_early: self.stage == GuidedStage::Rendered && self.caustic < CAUSTIC_GATE,
            ..plan.clone()
        }
    }
}

mod candidate;
mod pilot;
mod report;
mod stage;
pub use candidate::{default_candidates, Candidate, Candidates, AUTO_REUSE};
use pilot::{shared_denominator, Pilots};
use stage::{pilot_staged, Gates};
pub use stage::{GuidedStage, TRAINING_SAMPLE_COST};

#[cfg(test)]
mod tests;
