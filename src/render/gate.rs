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
}

impl Default for Gate {
    fn default() -> Self {
        Gate {
            readings: 0,
            last: None,
            verdict: Verdict::Undecided,
            margin: 1.0,
            first: GATE_FIRST,
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

    /// Take the reading of iteration `k`'s image `guided` against its probe `probe`, with the
    /// rays each traced per pixel sample; the verdict follows the module doc's rule.
    pub(super) fn read(
        &mut self,
        k: u32,
        (guided, guided_rays): (&IterationImage, f64),
        (probe, probe_rays): (&IterationImage, f64),
        width: usize,
    ) {
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
        let z = ratio.ln() / s;
        let z_margin = (ratio / self.margin).ln() / s;
        self.readings += 1;
        self.verdict = if z.is_nan() {
            // a black image (no variance in either) or no pixel read: nothing to gain
            if vg <= 0.0 && vp <= 0.0 {
                Verdict::Closed
            } else {
                Verdict::Open
            }
        } else if z_margin > GATE_Z_ALONE
            || (z_margin > GATE_Z && self.last.is_some_and(|r| r.z_margin > GATE_Z))
        {
            Verdict::Closed
        } else if z < -GATE_Z || self.readings >= GATE_PROBES {
            Verdict::Open
        } else {
            Verdict::Undecided
        };
        self.last = Some(GateReading {
            spp: 1 << k,
            ratio,
            z,
            z_margin,
        });
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
                 {} ({} probe{})",
                r.spp,
                r.ratio,
                r.z,
                if self.margin == 1.0 {
                    String::new()
                } else {
                    format!(" ({:.1} over {:.2}x)", r.z_margin, self.margin)
                },
                self.readings,
                if self.readings == 1 { "" } else { "s" }
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
mod tests {
    use super::*;
    use crate::film::Film;
    use glam::DVec3;

    /// An image of `w × h` pixels whose pixel `i` holds 8 samples, 4 at `1 − d(i)` and 4 at
    /// `1 + d(i)`: mean 1, variance of the mean `d(i)²·8/7/8`.
    fn image(w: u32, h: u32, d: impl Fn(usize) -> f64) -> IterationImage {
        let mut f = Film::new(w, h);
        for i in 0..f.len() {
            let (lo, hi) = (1.0 - d(i), 1.0 + d(i));
            f.add_pixel_sums(
                i,
                DVec3::splat(4.0 * (lo + hi)),
                DVec3::splat(4.0 * (lo * lo + hi * hi)),
                8,
            );
        }
        IterationImage::of(&f)
    }

    /// The two tests' images: 64 × 32 pixels (2048: the first probe at 64 spp, 2¹⁷ paths).
    const W: u32 = 64;
    const H: u32 = 32;
    const PIXELS: u64 = (W * H) as u64;

    /// A pixel's spread: 0.5, 0.6, 0.7 or 0.9 by pixel.
    fn spread(i: usize) -> f64 {
        [0.5, 0.6, 0.7, 0.9][i % 4]
    }

    /// The guided iteration's image, and a probe's: the spreads shifted by one pixel (so the
    /// paired terms differ) and scaled by `scale`.
    fn guided_and_probe(scale: f64) -> (IterationImage, IterationImage) {
        (
            image(W, H, spread),
            image(W, H, move |i| scale * spread(i + 1)),
        )
    }

    /// The rule of the module doc on images whose efficiencies are known. The pixels' spreads
    /// differ (`d` of 0.5, 0.6, 0.7 or 0.9 by pixel, the probe's pattern shifted by one pixel, so
    /// the paired terms differ and the standard error is not zero; each value is as frequent
    /// in both). Equal variances and rays leave the probe [`GUIDED_RAY_COST`] times as
    /// efficient, beyond [`GATE_Z_ALONE`]: the gate closes at once; 1.05× as efficient closes it
    /// at the second reading, not the first; a probe of 4× the variance is 1.5/4 as efficient
    /// (it opens at once); a probe of 1.5× the variance ties (undecided until the last probe,
    /// then open); black images close it.
    #[test]
    fn the_gate_closes_where_the_guide_loses_and_opens_where_it_wins() {
        let (w, h, pixels) = (W, H, PIXELS);
        let read = |gate: &mut Gate, scale: f64, k: u32| {
            assert!(gate.probes_at(k, pixels), "{gate:?} at {k}");
            let (guided, probe) = guided_and_probe(scale);
            gate.read(k, (&guided, 4.0), (&probe, 4.0), w as usize);
        };
        let first = (GATE_PATHS / pixels).trailing_zeros();
        assert!(!Gate::default().probes_at(first - 1, pixels));

        // Phong directions 1.5× as efficient: one reading is enough
        let mut same = Gate::default();
        read(&mut same, 1.0, first);
        assert!(same.closed(), "{same:?}");
        let r = same.last.unwrap();
        assert!((r.ratio / GUIDED_RAY_COST - 1.0).abs() < 1e-6, "{r:?}");
        assert!(r.z > GATE_Z_ALONE && r.spp == 64, "{r:?}");
        assert!(!same.probes_at(first + 1, pixels));

        // 1.05× as efficient, between GATE_Z and GATE_Z_ALONE: closed at the second reading
        let scale = (GUIDED_RAY_COST / 1.05).sqrt();
        let mut close = Gate::default();
        read(&mut close, scale, first);
        assert_eq!(close.verdict, Verdict::Undecided, "{close:?}");
        let z = close.last.unwrap().z;
        assert!(z > GATE_Z && z < GATE_Z_ALONE, "{close:?}");
        read(&mut close, scale, first + 1);
        assert!(close.closed(), "{close:?}");

        let mut noisy = Gate::default();
        read(&mut noisy, 2.0, first);
        assert_eq!(noisy.verdict, Verdict::Open, "{noisy:?}");
        assert!((noisy.last.unwrap().ratio / (GUIDED_RAY_COST / 4.0) - 1.0).abs() < 1e-6);
        assert!(!noisy.probes_at(first + 1, pixels));

        // a losing reading, then ties: not closed
        let mut tie = Gate::default();
        read(&mut tie, scale, first);
        for j in 1..GATE_PROBES {
            assert_eq!(tie.verdict, Verdict::Undecided, "{tie:?}");
            read(&mut tie, GUIDED_RAY_COST.sqrt(), first + j);
            assert!(tie.last.unwrap().z.abs() < 1e-3, "{tie:?}");
        }
        assert_eq!(tie.verdict, Verdict::Open, "{tie:?}");
        assert_eq!(tie.readings, GATE_PROBES);

        let black = image(w, h, |_| 0.0);
        let mut gate = Gate::default();
        gate.read(first, (&black, 4.0), (&black, 4.0), w as usize);
        assert!(gate.closed(), "{gate:?}");
    }

    /// [`DISCARDED_MARGIN`]: where the training is discarded, a probe that ties with the guide
    /// (ratio 1, which leaves [`Gate::default`] undecided at z ≈ 0) reads
    /// `ln(1/0.9)/s` against the margin, here beyond [`GATE_Z_ALONE`]: closed at once; a
    /// guide 1.5× ahead still opens it, and one 1.05× ahead, within the margin, closes it
    /// (where the training is kept it opens); the record names the margin.
    #[test]
    fn a_discarded_training_asks_the_guide_to_clear_a_margin() {
        let read = |keeps: bool, ratio: f64| {
            // the probe's variance for `ratio`: e_p/e_g = V_g·c_g/(V_p·c_p)
            let (guided, probe) = guided_and_probe((GUIDED_RAY_COST / ratio).sqrt());
            let mut gate = Gate::new(keeps);
            let first = (GATE_PATHS / PIXELS).trailing_zeros();
            gate.read(first, (&guided, 4.0), (&probe, 4.0), W as usize);
            gate
        };
        let (kept, discarded) = (read(true, 1.0), read(false, 1.0));
        assert_eq!(kept.verdict, Verdict::Undecided, "{kept:?}");
        assert!(kept.last.unwrap().z.abs() < 1e-3, "{kept:?}");
        assert!(discarded.closed(), "{discarded:?}");
        let (rk, rd) = (kept.last.unwrap(), discarded.last.unwrap());
        assert!((rd.ratio / rk.ratio - 1.0).abs() < 1e-9, "{rk:?} {rd:?}");
        assert!(
            rd.z_margin > GATE_Z_ALONE && (rd.z - rk.z).abs() < 1e-9,
            "{rd:?}"
        );
        assert!(
            discarded.record().contains("over 0.90x"),
            "{}",
            discarded.record()
        );
        assert!(!kept.record().contains("over"), "{}", kept.record());
        assert_eq!(read(false, 1.0 / 1.5).verdict, Verdict::Open);
        // 1.05× ahead: a gain without the margin, a loss within it (these images' z is sharp:
        // beyond GATE_Z both ways, and closing goes first)
        let within = read(false, 1.0 / 1.05);
        let r = within.last.unwrap();
        assert!(r.z < -GATE_Z && r.z_margin > GATE_Z_ALONE, "{r:?}");
        assert!(within.closed(), "{within:?}");
        assert_eq!(read(true, 1.0 / 1.05).verdict, Verdict::Open);
    }

    /// The denominator's box: a probe that meets a rare bright path (one pixel in 9, on a
    /// 3-pixel grid, holds one sample of 72 among its 8, the others none: mean 1 over any 9×9
    /// box, as the guided image's 1 everywhere) reads its variance against the box's mean, as
    /// against the true image: per pixel `81/9 = 9` on average against the guided image's
    /// `(2/7)/8` (252×; the box's mean is 1 in the interior and within about 20% of it at the
    /// border). Against each pixel's own pooled mean (no box) its bright pixels divide by 5²
    /// and the guided image's dark ones by 0.5²: it reads about 3×.
    #[test]
    fn the_denominator_is_the_pooled_image_averaged_over_a_box() {
        let (w, h) = (64u32, 64u32);
        let mut guided = Film::new(w, h);
        let mut probe = Film::new(w, h);
        for i in 0..guided.len() {
            // guided: 8 samples, 4 at 0.5 and 4 at 1.5 (mean 1, sample variance 2/7)
            guided.add_pixel_sums(i, DVec3::splat(8.0), DVec3::splat(10.0), 8);
            let (x, y) = (i as u32 % w, i as u32 / w);
            let (s, s2) = if x % 3 == 0 && y % 3 == 0 {
                (72.0, 72.0 * 72.0)
            } else {
                (0.0, 0.0)
            };
            probe.add_pixel_sums(i, DVec3::splat(s), DVec3::splat(s2), 8);
        }
        let (g, p) = (IterationImage::of(&guided), IterationImage::of(&probe));
        let ratio = |blur: usize| {
            let t = crate::render::combine::shared_rel_terms(&[&g, &p], w as usize, blur);
            t[1].iter().sum::<f64>() / t[0].iter().sum::<f64>()
        };
        let truth = 9.0 / (2.0 / 7.0 / 8.0);
        let boxed = ratio(GATE_BLUR);
        assert!(
            (boxed / truth - 1.0).abs() < 0.25,
            "{boxed} against {truth}"
        );
        let own = ratio(0);
        assert!(own < 5.0, "{own}");
    }

    /// The first reading comes at the first iteration [`Gate::probes_at`] probes, and the
    /// training reaches it only where its spp (and, at a known speed, its time) holds the
    /// iterations up to it: the night hall at its default (192×108, 16 spp: a budget of 8)
    /// first reads at 8 spp, after 15 of training, so not; Mitsuba's box (256², 16 spp) at 4,
    /// after 7, so it does.
    #[test]
    fn the_training_reaches_the_first_reading_or_not() {
        for pixels in [1u64, 96 * 64, 192 * 108, 256 * 256, 1 << 17, 1920 * 1080] {
            let k = first_probe(pixels);
            assert!(Gate::default().probes_at(k, pixels), "{pixels}");
            assert!(k == GATE_FIRST || !Gate::default().probes_at(k - 1, pixels));
        }
        assert_eq!(first_probe(192 * 108), 3);
        assert_eq!(first_probe(256 * 256), 2);
        let budget = |spp: u64, secs: Option<f64>| super::super::TrainingBudget {
            spp,
            time: secs.map(std::time::Duration::from_secs_f64),
        };
        assert!(!reads_within(budget(8, None), 192 * 108, None));
        assert!(reads_within(budget(15, None), 192 * 108, None));
        assert!(reads_within(budget(8, None), 256 * 256, None));
        // under a time limit, at 0.02 s a training spp: 15 spp take 0.3 s
        let fast = Some(0.02);
        assert!(reads_within(budget(1 << 20, Some(3.3)), 192 * 108, fast));
        assert!(!reads_within(budget(1 << 20, Some(0.29)), 192 * 108, fast));
        // with no speed known (no time limit) the spp decide
        assert!(reads_within(budget(15, Some(0.01)), 192 * 108, None));
    }
}
