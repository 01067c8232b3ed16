//! The guide's gate (issue 51): a guided render that finds, during its training, that the
//! guide does not pay renders the rest of its image without it.
//!
//! A guide costs at every vertex (the S-tree lookup, the quadtree descents: about
//! [`GUIDED_RAY_COST`] times the time of a ray without it), and where nothing indirect is to
//! be learned (light that next-event estimation already carries, glossy reflections the Phong
//! lobe already samples) it lowers no variance: on the glossy plates a guided render reached
//! 0.46× the equal-time efficiency of Phong directions. So from the first training iteration
//! of at least [`GATE_PATHS`] paths, while the gate is undecided and for at most
//! [`GATE_PROBES`] iterations, the iteration is followed by a *probe*: the same spp with the
//! guide off (Phong directions under the same MIS), on seeds of its own. The two images'
//! efficiencies `e = 1/(V·c)` are compared:
//!
//! - `V`: each image's variance of the mean per pixel (its samples' variance over their count),
//!   relative to one denominator for both, `F̄(p)² + ε`, with `F̄` the two images pooled and
//!   then averaged over a box of `2·`[`GATE_BLUR`]` + 1` pixels a side. The blur is what makes
//!   the reading honest at a few samples: with each pixel's own pooled mean as the denominator,
//!   a pixel whose samples met a rare bright path divides its large variance by its large mean,
//!   so the estimator that finds the light by rare paths (Phong directions in a room lit
//!   through a door) looks as good as the one that finds it often: on the door at 16 spp
//!   (128×96) the per-pixel denominator read the probe 2.3× as efficient as the guide, the
//!   blurred one 0.42× (guiding wins about 3× there at equal time).
//! - `c`: the rays a sample traced, a guided one's weighed [`GUIDED_RAY_COST`]: a count, so the
//!   decision and the image are the same on any thread count and for any clock.
//!
//! `z = ln(e_probe/e_guided)/s`, with `s` the standard error of `ln(V_probe/V_guided)` by the
//! delta method over the pixels' *paired* terms (`V_p⁻¹ t_p(i) − V_g⁻¹ t_g(i)`): what the two
//! images share, a glossy highlight noisy in both, cancels, where unpaired errors read the
//! plates' 1.8× at z 1.6–4 and paired at 8–61. The gate closes where two readings in a row
//! have `z >` [`GATE_Z`] (a guide still learning loses its first readings: see
//! [`GATE_PATHS`]) or one has `z >` [`GATE_Z_ALONE`], opens for good where one has
//! `z < −GATE_Z`, and stays open after [`GATE_PROBES`] undecided readings (the render was asked
//! to guide). Where the render discards its training images (path reuse), what closes the
//! gate is `z_m = ln(e_probe/(m·e_guided))/s` with the margin `m =` [`DISCARDED_MARGIN`]: the
//! guide must be ahead by `1/m` to repay a training thrown away; what opens it is still `z`.
//! A closed gate ends the training, and the final iteration samples with Phong directions.
//!
//! **The early look** ([`Gate::looking_early`]). Where the training is discarded, every
//! iteration waited for is paid in full. `--strategy auto`'s guided twin, where its probe found
//! no light coming as caustics, also reads the iteration before the first probe's (2¹⁶ paths or
//! more, from [`GATE_FIRST`]) against the first half of that probe's samples, rendered then; it
//! closes there where `z_m >` [`GATE_Z_ALONE`], as one reading alone closes the gate, and else
//! counts nothing: the probe renders its second half and reads as it would have. In the night
//! hall (192×108) the twin closes at 4 spp instead of 8, after 7 spp of training and 4 of probe
//! instead of 15 and 8 (`docs/guiding.md`). Not for every render: an immature guide has not yet
//! found the caustics it will find, and on the lamp behind glass (128², `--directions guided
//! --reuse 4`, seeds 1–12) the early reading closed two gates of twelve (z_m 6.0 and 8.4) where
//! the guide goes on to win; the door, the gap and door-dark at 96×64 read the guide ahead.
//!
//! **What the image keeps.** Every probe is an unbiased image of the pixel. Where the gate
//! closes, the probes are kept with the training iterations and combined with the final
//! iteration by inverse variance (`render::combine`): they are the final iteration's estimator.
//! Where it stays open they are dropped: Phong images where the guide wins have heavier tails
//! than the guided ones, their variances read low at a few samples per pixel, and kept they
//! cost the gap 1.46× in relMSE at 10 s. The decision is a function of all the training's and
//! probes' pixels, as the guide itself is; the combination weighs a pixel by the other half of the image's variances, and the
//! decision's dependence on one pixel's samples is of the same second order as the guide's.

use super::auto::GUIDED_RAY_COST;
use super::combine::IterationImage;

/// The fewest paths (spp × pixels) of a training iteration followed by a probe. How well the
/// guide has learned depends on the paths it learned from, not on the spp, and an immature
/// guide loses where a trained one wins: on the lamp behind glass (seeds 1, 2) the readings at
/// 110k paths (96×72 at 16 spp) read Phong directions better with z 4.2 and 5.1, and at 196k
/// (256×192 at 4 spp) with z 2.1 and 4.8, where from 221k on the guide wins (z −1.9 to −13);
/// the door read z up to 3.4 at 55k paths and the guide wins from 110k (z −2.8 to −34). The
/// glossy plates read Phong 1.4–1.9× as efficient from 196k paths on (z 4.7 to 61). So the
/// first probe comes at 2¹⁷ paths, and the gate closes only on two readings in a row.
pub const GATE_PATHS: u64 = 1 << 17;
/// The first training iteration that may be probed (4 spp: a pixel's variance needs two
/// samples, and at 1–2 spp the guide has learned from at most one sample per pixel).
pub const GATE_FIRST: u32 = 2;
/// Probes a render reads at most, at consecutive iterations from the first of [`GATE_PATHS`]
/// paths; undecided after them, the gate stays open.
pub const GATE_PROBES: u32 = 3;
/// The z beyond which the gate decides (closing, on two readings in a row).
pub const GATE_Z: f64 = 3.0;
/// The z beyond which one reading closes the gate. A guide still learning read Phong
/// directions better at z up to 5.1 (the lamp: see [`GATE_PATHS`]; at 96×72 its first readings,
/// seeds 1–6, are all the guide's, z −3.1 to −5.3); the glossy plates read z 22–28 at their
/// first probe at 256×192 (196k paths), and the night hall (192×108) z 6.5–8.1 at its first
/// (8 spp), Phong ahead 1.2× where guided+reuse4 reaches 0.57× of reuse4 at 10 s. Waiting for a
/// second reading cost the plates an iteration of 8 spp and its probe (about 8% of a 10-s
/// render), the night hall 16 spp and its probe: auto rendering guided+reuse4 there reached
/// 0.70× of reuse4 at 10 s waiting for a second reading beyond [`GATE_Z`] (10 before), 0.84×
/// closing at the first beyond 6.
pub const GATE_Z_ALONE: f64 = 6.0;
/// The margin a guide must clear where the render discards its training images (path reuse,
/// `--training-images discard`): the gate closes on `ratio / margin` read against one, so it
/// reads the guide as losing unless it is ahead of Phong directions by `1/margin` ≈ 1.11× per
/// cost (it opens, as everywhere, where the guide is ahead beyond the noise at all: a margin
/// there delayed the Cornell box's opening to the third probe, 0.94× at 10 s). A
/// discarded training is paid for by the final iteration alone (a third of the render's time,
/// not half of it kept), and the readings are taken without path reuse, where the guide's gain
/// is not the reused render's: in the night hall (192×108, seeds 7–18 at 10 s) the readings
/// fall as the guide matures to 1.06–1.13 at 16 spp and 0.96–1.03 at 32 (a tie: four of
/// twelve renders stayed undecided and guided), and guided+reuse4 without the gate reaches
/// 0.69× of reuse4 at 10 s; on the Cornell box the readings at 8–16 spp are 0.73–0.92 and
/// guided+reuse4 wins 1.29× there, on the gap 0.34–0.88 (it wins about 2×). 0.9 lies between
/// the tie that loses and the Cornell box's lead. With it, auto's guided+reuse4 twin closes in
/// the night hall at its first reading in 11 of 12 renders (seeds 7–18; z 6.2–14.8 against the
/// margin), and auto reaches 0.92× of `--reuse 4` at 10 s (seeds 1–18 as nine pairs; 0.76×
/// on seeds 7–18 before); the door's, the gap's and the Cornell box's gates decide as before
/// (seeds 1–2, 1–6, 1–8), their highest first reading against the margin 4.2 (the gap's
/// immature guide, 1.43 at z 3.3), the lamp's at 256×192 with `--reuse 4` opening at 4–8 spp.
/// (With the early look, auto's twin closes at 4 spp there, and auto reaches 0.97×.)
pub const DISCARDED_MARGIN: f64 = 0.9;
/// The half-width in pixels of the box that averages the reading's denominator.
pub const GATE_BLUR: usize = 4;

/// One reading of the gate: a training iteration against its probe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GateReading {
    /// The iteration's (and the probe's) samples per pixel.
    pub spp: u64,
    /// The probe's efficiency over the guided iteration's, `e_probe/e_guided`.
    pub ratio: f64,
    /// `ln(ratio)` over its standard error: below `−`[`GATE_Z`] the gate opens.
    pub z: f64,
    /// `ln(ratio / margin)` over the same standard error (the margin: one, or
    /// [`DISCARDED_MARGIN`]): what closes the gate.
    pub z_margin: f64,
}

/// The first training iteration (`2^k` spp) a render of `pixels` pixels probes: the first
/// from [`GATE_FIRST`] of at least [`GATE_PATHS`] paths ([`Gate::probes_at`]).
pub fn first_probe(pixels: u64) -> u32 {
    (GATE_FIRST..31)
        .find(|&k| (1u64 << k).saturating_mul(pixels) >= GATE_PATHS)
        .unwrap_or(31)
}

/// Whether the training of a guided render of `pixels` pixels under `budget` reaches its
/// gate's first reading ([`first_probe`]): its iterations of 1, 2, …, `2^k` spp, `2^(k+1) − 1`
/// in all, within the budget's spp, and, at `per_spp` seconds per training spp of the image
/// where it is known, within its time (the training starts an iteration where the time so far
/// and twice the last one's fit, about the same sum). Where it does not, the gate never reads
/// and the guide renders the image unjudged.
pub fn reads_within(budget: super::TrainingBudget, pixels: u64, per_spp: Option<f64>) -> bool {
    let spp = (2u64 << first_probe(pixels)) - 1;
    let time = match (budget.time, per_spp) {
        (Some(t), Some(s)) => s * spp as f64 <= t.as_secs_f64(),
        _ => true,
    };
    spp <= budget.spp && time
}

/// What the gate decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// The guide loses beyond the noise: the rest of the image without it.
    Closed,
    /// The guide wins beyond the noise, or the last probe left it undecided: guided.
    Open,
    /// Not yet decided: probe again at the next iteration.
    Undecided,
}

/// The gate of one render: its readings and its verdict.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gate {
    /// The readings taken (the last one decided).
    pub readings: u32,
    /// The last reading.
    pub last: Option<GateReading>,
    /// The verdict after the last reading.
    pub verdict: Verdict,
    /// What the probe's efficiency over the guide's is tested against: one, or
    /// [`DISCARDED_MARGIN`] where the training images are discarded.
    pub margin: f64,
    /// The iteration of the first probe ([`first_probe`]; `2^first` spp), set by the training
    /// that gates: a gate with no reading says where its first would have come.
    pub first: u32,
    /// Whether it takes the early look ([`Gate::looking_early`]).
    pub early: bool,
}

impl Default for Gate {
    fn default() -> Self {
        Gate {
            readings: 0,
            last: None,
            verdict: Verdict::Undecided,
            margin: 1.0,
            first: GATE_FIRST,
            early: false,
        }
    }
}

impl Gate {
    /// The gate of a render that keeps its training images (`keeps`), or discards them and
    /// asks the guide to clear [`DISCARDED_MARGIN`].
    pub fn new(keeps: bool) -> Self {
        let margin = if keeps { 1.0 } else { DISCARDED_MARGIN };
        Gate {
            margin,
            ..Gate::default()
        }
    }

    /// The gate, taking the early look where `early` asks for it and the training is discarded
    /// (the margin): at the iteration before its first probe's, against the first half of that
    /// probe (the module doc's early look; auto's guided twin where no light came as caustics,
    /// [`super::PassPlan::gate_early`]).
    pub fn looking_early(self, early: bool) -> Self {
        Gate {
            early: early && self.margin != 1.0,
            ..self
        }
    }

    /// Whether training iteration `k` over `pixels` pixels is followed by a probe: from the
    /// first probe's iteration ([`first_probe`], the one rule auto's staging reads too) while
    /// undecided, for at most [`GATE_PROBES`] readings.
    pub fn probes_at(&self, k: u32, pixels: u64) -> bool {
        self.verdict == Verdict::Undecided
            && k >= first_probe(pixels)
            && self.readings < GATE_PROBES
    }

    /// Whether the final iteration renders without the guide.
    pub fn closed(&self) -> bool {
        self.verdict == Verdict::Closed
    }

    /// The reading of iteration `k`'s image `guided` against its probe `probe`, with the rays
    /// each traced per pixel sample (the module doc's `z` and `z_m`), and the two images'
    /// mean terms `(V_g, V_p)`.
    fn reading(
        &self,
        k: u32,
        (guided, guided_rays): (&IterationImage, f64),
        (probe, probe_rays): (&IterationImage, f64),
        width: usize,
    ) -> (GateReading, f64, f64) {
        let terms = super::combine::shared_rel_terms(&[guided, probe], width, GATE_BLUR);
        let (tg, tp) = (&terms[0], &terms[1]);
        let n = tg.len().max(1) as f64;
        let (vg, vp) = (tg.iter().sum::<f64>() / n, tp.iter().sum::<f64>() / n);
        let ratio = (vg * guided_rays * GUIDED_RAY_COST) / (vp * probe_rays);
        // ln(vp/vg) by the delta method over the pixels' paired terms: what the two images
        // share (a bright pixel is noisy in both) cancels
        let (mut s1, mut s2) = (0.0, 0.0);
        for (a, b) in tg.iter().zip(tp) {
            let d = b / vp - a / vg;
            s1 += d;
            s2 += d * d;
        }
        let s = ((s2 / n - (s1 / n).powi(2)).max(0.0) / n).sqrt();
        let reading = GateReading {
            spp: 1 << k,
            ratio,
            z: ratio.ln() / s,
            z_margin: (ratio / self.margin).ln() / s,
        };
        (reading, vg, vp)
    }

    /// Take the reading of iteration `k`'s image `guided` against its probe `probe`, with the
    /// rays each traced per pixel sample; the verdict follows the module doc's rule.
    pub(super) fn read(
        &mut self,
        k: u32,
        guided: (&IterationImage, f64),
        probe: (&IterationImage, f64),
        width: usize,
    ) {
        let (r, vg, vp) = self.reading(k, guided, probe, width);
        self.readings += 1;
        self.verdict = if r.z.is_nan() {
            // a black image (no variance in either) or no pixel read: nothing to gain
            if vg <= 0.0 && vp <= 0.0 {
                Verdict::Closed
            } else {
                Verdict::Open
            }
        } else if r.z_margin > GATE_Z_ALONE
            || (r.z_margin > GATE_Z && self.last.is_some_and(|l| l.z_margin > GATE_Z))
        {
            Verdict::Closed
        } else if r.z < -GATE_Z || self.readings >= GATE_PROBES {
            Verdict::Open
        } else {
            Verdict::Undecided
        };
        self.last = Some(r);
    }

    /// Whether training iteration `k` over `pixels` pixels is followed by the early look: the
    /// gate looks early ([`Gate::looking_early`]), has read nothing, and `k` is the iteration
    /// before the first probe's ([`first_probe`]), from [`GATE_FIRST`].
    pub fn looks_early_at(&self, k: u32, pixels: u64) -> bool {
        self.early
            && self.readings == 0
            && self.verdict == Verdict::Undecided
            && k >= GATE_FIRST
            && k + 1 == first_probe(pixels)
    }

    /// The early look at iteration `k`'s image `guided` against `half`, the first half of the
    /// next iteration's probe (`2^k` spp of its `2^(k+1)`): it closes the gate where the reading
    /// against the margin is beyond [`GATE_Z_ALONE`], as one reading alone closes it, and else
    /// leaves the gate as it was (no reading counted: the first probe, of both halves, reads).
    pub(super) fn look_early(
        &mut self,
        k: u32,
        guided: (&IterationImage, f64),
        half: (&IterationImage, f64),
        width: usize,
    ) {
        let (r, _, _) = self.reading(k, guided, half, width);
        if r.z_margin > GATE_Z_ALONE {
            self.readings = 1;
            self.verdict = Verdict::Closed;
            self.last = Some(r);
        }
    }

    /// The verdict and the last reading, as the metadata key `guide_gate` holds them:
    /// `closed at 8 spp: Phong directions 1.79x as efficient as the guide, z 4.2 (1 probe)`;
    /// where the training ended before the first probe, `unread (…)`: the guide rendered the
    /// image unjudged.
    pub fn record(&self) -> String {
        let verdict = match self.verdict {
            Verdict::Closed => "closed",
            Verdict::Open if self.last.is_some_and(|r| r.z < -GATE_Z) => "open",
            _ => "open (undecided)",
        };
        match self.last {
            Some(r) => format!(
                "{verdict} at {} spp: Phong directions {:.2}x as efficient as the guide, z {:.1}\
                 {} ({})",
                r.spp,
                r.ratio,
                r.z,
                if self.margin == 1.0 {
                    String::new()
                } else {
                    format!(" ({:.1} over {:.2}x)", r.z_margin, self.margin)
                },
                match self.readings {
                    _ if r.spp < 1 << self.first => "an early look, half a probe".to_string(),
                    1 => "1 probe".to_string(),
                    n => format!("{n} probes"),
                }
            ),
            None => format!(
                "unread (the training ended before its first probe, at {} spp)",
                1u64 << self.first
            ),
        }
    }

    /// One line for `--stats`: the record, and what the final iteration did.
    pub fn summary(&self) -> String {
        let then = if self.closed() {
            "the rest rendered with Phong directions"
        } else {
            "the guide kept"
        };
        format!("guiding: gate {}; {then}\n", self.record())
    }
}

#[cfg(test)]
mod tests;
