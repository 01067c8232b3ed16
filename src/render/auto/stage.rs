//! The staging of `--strategy auto`'s guided candidates (the module doc above): which pilots
//! render, and whether a guided twin renders without one. A twin renders only where its gate
//! can judge it: where the twin's training reaches the gate's first reading
//! ([`crate::render::gate::reads_within`]) before its budget ends. Where it cannot (a render of
//! few samples: the night hall at its default 16 spp trains 7 spp, and its gate first reads
//! at 8), the twin would render guided without a reading, unjudged, in place of the unguided
//! choice the pilots measured (there, guided+reuse4 where the guide reads 1.1–1.2× behind
//! Phong directions); then the unguided choice renders ([`GuidedStage::Unread`]).

use super::*;

/// What a training sample costs (a sample of a guided training iteration: the guide's lookups
/// and descents, and the records it learns from), in samples of the first candidate's probe:
/// on Mitsuba's box (256², 2 threads) a guided render's training 1.0 M samples/s where mis
/// renders 2.0 M; [`GUIDED_RAY_COST`]'s measurement with the training, 1.7–2.2.
pub const TRAINING_SAMPLE_COST: f64 = 2.0;

/// What the gates read from the probe ([`PROBE_SPP`]): whether enough of the first candidate's
/// light was caustic ([`CAUSTIC_GATE`]), and whether too little was indirect ([`INDIRECT_GATE`]);
/// and what the reach of a twin's gate needs ([`Pilots::twin_reads`]): the first candidate's
/// seconds per spp of the image under a time limit, and when the pilots began.
#[derive(Clone, Copy, Debug)]
pub(super) struct Gates {
    pub(super) caustic: bool,
    pub(super) direct: bool,
    pub(super) per_spp: Option<f64>,
    pub(super) start: Instant,
}

/// The pilots of `candidates` at `spp`, staged (the module doc): where the probe's light is
/// caustic enough and the first's guided twin is listed and reads its gate (the module doc of
/// this file), none (the twin renders); else the first and the other unguided ones, and where
/// one of them beat the first or the light is caustic, no more where the guided twin of their
/// choice is listed (it renders where it reads its gate; else the unguided choice does), else
/// every guided candidate. Where too little of the probe's light is indirect, no candidate with
/// path reuse is piloted; where no candidate but the first is left to pilot, none is (the first
/// is chosen). The candidates piloted, their pilots and what became of the guided ones.
pub(super) fn pilot_staged(
    pilots: &mut Pilots,
    candidates: &[Candidate],
    spp: u32,
    gates: Gates,
) -> Result<(Vec<usize>, Vec<pilot::Pilot>, GuidedStage)> {
    let n = candidates.len();
    let guided = |k: usize| k > 0 && candidates[k].strategy.directions == Directions::Guided;
    let staged = (1..n).any(|k| !guided(k)) && (1..n).any(guided);
    let twin_of = |c: Candidate| (1..n).find(|&k| guided(k) && candidates[k] == c.guided());
    let reads = |pilots: &Pilots, c: Candidate| {
        let elapsed = gates.start.elapsed();
        pilots.twin_reads(
            c.guided(),
            gates.per_spp.map(|s| s * TRAINING_SAMPLE_COST),
            elapsed,
        )
    };
    let (mut ks, mut done) = (Vec::new(), Vec::new());
    let first = candidates[0];
    if staged && gates.caustic && twin_of(first).is_some() && reads(pilots, first) {
        return Ok((ks, done, GuidedStage::Rendered));
    }
    let shares = |k: &usize| !(gates.direct && candidates[*k].reuse > 1);
    let width = pilots.width;
    let mut pilot = |ks: &mut Vec<usize>, done: &mut Vec<pilot::Pilot>, k: usize| {
        if ks.is_empty() && k > 0 {
            done.push(pilots.run(0, spp)?);
            ks.push(0);
        }
        done.push(pilots.run(k, spp)?);
        ks.push(k);
        Ok::<_, crate::error::Error>(())
    };
    for k in (1..n).filter(|&k| !staged || !guided(k)).filter(shares) {
        pilot(&mut ks, &mut done, k)?;
    }
    let winner = match done.is_empty() {
        true => first,
        false => done[decide(&shared_denominator(width, &done)).0].candidate,
    };
    if !staged || !(gates.caustic || winner != first) {
        return Ok((ks, done, GuidedStage::Shut));
    }
    if twin_of(winner).is_some() {
        let stage = match reads(pilots, winner) {
            true => GuidedStage::Rendered,
            false => GuidedStage::Unread,
        };
        return Ok((ks, done, stage));
    }
    for k in (1..n).filter(|&k| guided(k)).filter(shares) {
        pilot(&mut ks, &mut done, k)?;
    }
    Ok((ks, done, GuidedStage::Piloted))
}

/// What became of the guided candidates of a list that stages them (the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GuidedStage {
    /// None came in after the unguided pilots: no unguided candidate beat the first, and too
    /// little of the first's light was caustic. (A list that does not stage its guided
    /// candidates, one with no unguided candidate but the first, pilots them with the rest.)
    Shut,
    /// Piloted after the unguided ones, every guided candidate (its guide trained first on the
    /// pilots' strip): the unguided pilots' choice has no guided twin in the list.
    Piloted,
    /// The guided twin ([`Candidate::guided`]) of the unguided pilots' choice (of the first
    /// alone, where its light is caustic enough: [`CAUSTIC_GATE`]) is listed: it is rendered
    /// without a pilot, its guide trained over the image as `--directions guided` trains
    /// it, and its gate ([`crate::render::gate`]) rendering the rest with Phong directions
    /// where the guide loses.
    Rendered,
    /// The guided twin of the unguided pilots' choice is listed, but its training would end
    /// before its gate's first reading (this file's module doc): the unguided choice renders.
    Unread,
}
