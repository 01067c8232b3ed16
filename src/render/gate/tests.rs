//! The gate's rule on images whose efficiencies are known.

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

/// The early look ([`Gate::look_early`]): only a gate that discards its training and is asked
/// to looks, at the iteration before the first probe's and not from below [`GATE_FIRST`];
/// a tie (beyond [`GATE_Z_ALONE`] against the margin: the test above) closes it there,
/// counted as a reading and named in the record; a guide 1.5× ahead leaves it as it was,
/// unread, to probe at the first probe's iteration.
#[test]
fn the_early_look_closes_only_where_one_reading_would() {
    let first = (GATE_PATHS / PIXELS).trailing_zeros();
    assert!(!Gate::new(true).looking_early(true).early);
    assert!(!Gate::new(false).looking_early(false).early);
    let gate = Gate::new(false).looking_early(true);
    assert!(gate.early && gate.looks_early_at(first - 1, PIXELS));
    assert!(!gate.looks_early_at(first, PIXELS) && !gate.looks_early_at(first - 2, PIXELS));
    // 2¹⁶ pixels: the first probe at GATE_FIRST, nothing before it to look at
    let big = 1u64 << 16;
    assert_eq!(first_probe(big), GATE_FIRST);
    assert!(!gate.looks_early_at(GATE_FIRST - 1, big));
    let mut gate = Gate { first, ..gate };
    let look = |gate: &mut Gate, ratio: f64| {
        let (guided, probe) = guided_and_probe((GUIDED_RAY_COST / ratio).sqrt());
        gate.look_early(first - 1, (&guided, 4.0), (&probe, 4.0), W as usize);
    };
    let mut ahead = gate;
    look(&mut ahead, 1.0 / 1.5);
    assert_eq!(ahead, gate);
    assert!(ahead.probes_at(first, PIXELS));
    look(&mut gate, 1.0);
    assert!(gate.closed() && gate.readings == 1, "{gate:?}");
    let r = gate.last.unwrap();
    assert!(
        r.spp == 1 << (first - 1) && r.z_margin > GATE_Z_ALONE,
        "{r:?}"
    );
    assert!(
        gate.record().contains("(an early look, half a probe)"),
        "{}",
        gate.record()
    );
    assert!(!gate.probes_at(first, PIXELS));
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
