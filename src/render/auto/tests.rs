//! Unit tests of `--strategy auto`'s rule, names and pilot sizes.

use super::pilot::Pilot;
use super::*;

fn row(candidate: Candidate, rel_mse: f64, se: f64, cost: f64) -> PilotRow {
    PilotRow {
        candidate,
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
fn candidates_are_named_as_parsed() {
    let c = Candidates::parse(
        "mis, mis+reuse4,stratified+guided+mis+reuse2,importance+reuse1,stratified+guided+mis+ears",
    )
    .unwrap()
    .0;
    let names: Vec<String> = c.iter().map(Candidate::to_string).collect();
    assert_eq!(
        names,
        [
            "mis",
            "mis+reuse4",
            "stratified+guided+mis+reuse2",
            "importance",
            "stratified+guided+mis+ears"
        ]
    );
    assert_eq!(c[1].strategy, Strategy::default());
    assert_eq!((c[1].reuse, c[3].reuse), (4, 1));
    assert_eq!(
        (c[0].roulette, c[4].roulette),
        (Roulette::Classic, Roulette::Ears)
    );
    for n in &names {
        assert_eq!(Candidate::parse(n).unwrap().to_string(), *n);
    }
    for bad in [
        "mis+reuse0",
        "mis+reuse5",
        "mis+reuse",
        "mis+reusex",
        "nosuch+reuse2",
        "mis+reuse2+ears",
        "mis+ears+reuse2",
        "+ears",
    ] {
        assert!(Candidate::parse(bad).is_err(), "{bad}");
    }
    assert!(Candidate::parse("mis+reuse9")
        .unwrap_err()
        .contains("+reuseK"));
    for bad in ["mis+reuse2+ears", "mis+ears+reuse2"] {
        assert!(Candidate::parse(bad)
            .unwrap_err()
            .contains("does not combine"));
    }
    let d = default_candidates();
    assert_eq!(
        d.iter().map(|c| c.reuse).collect::<Vec<_>>(),
        [1, AUTO_REUSE, 1, AUTO_REUSE]
    );
    let guided = |c: &Candidate| c.strategy.directions == Directions::Guided;
    assert_eq!(
        d.iter().map(guided).collect::<Vec<_>>(),
        [false, false, true, true]
    );
    assert!(d.iter().all(|c| c.roulette == Roulette::Classic));
}

#[test]
fn pilots_take_a_sixteenth_in_whole_rounds_of_replicates() {
    assert_eq!(pilot_spp(1), 4);
    assert_eq!(pilot_spp(64), 4);
    assert_eq!(pilot_spp(256), 16);
    assert_eq!(pilot_spp(1000), 60);
    assert_ne!(pilot_seed(0), pilot_seed(1));
    assert_ne!(pilot_seed(0), 0);
}

#[test]
fn early_pilots_take_a_quarter_and_decide_only_beyond_doubt() {
    assert_eq!(early_spp(4), 4);
    assert_eq!(early_spp(8), 4);
    assert_eq!(early_spp(16), 4);
    assert_eq!(early_spp(60), 12);
    let [a, b] = [default_candidates()[0], default_candidates()[1]];
    // twice as efficient, relMSE known to 5%: z = ln 2 / (0.05·√2) = 9.8, ratio 2: decided
    let clear = [row(a, 0.02, 0.001, 100.0), row(b, 0.01, 0.0005, 100.0)];
    assert!(decide(&clear).1 > EARLY_Z && decided_early(&clear));
    // 1.4 times, known to 2%: z = 11.9 but within what the pilots' times may vary: not decided
    let close = [row(a, 0.014, 2.8e-4, 100.0), row(b, 0.01, 2e-4, 100.0)];
    assert!(decide(&close).1 > EARLY_Z && !decided_early(&close));
    // twice, known to 10%: z = 4.9, a switch (above SWITCH_Z) but not beyond doubt
    let noisy = [row(a, 0.02, 0.002, 100.0), row(b, 0.01, 0.001, 100.0)];
    assert_eq!(decide(&noisy).0, 1);
    assert!(!decided_early(&noisy));
    // the first kept: the full pilots decide
    assert!(!decided_early(&[
        row(a, 0.01, 1e-4, 1.0),
        row(b, 0.02, 1e-4, 1.0)
    ]));
}

/// A guided candidate's guide trains on an eighth of the render's budget: of its time limit,
/// and of its samples, as samples per pixel of the strip (a quarter of the image: 4× as many).
#[test]
fn a_guided_candidates_guide_trains_on_an_eighth_of_the_budget() {
    let b = guide_budget(1024, 0.25, Some(Duration::from_secs(8)));
    assert_eq!(b.spp, 512);
    assert_eq!(b.time, Some(Duration::from_secs(1)));
    assert_eq!(guide_budget(1024, 1.0, None).spp, 128);
    assert_eq!(guide_budget(4, 0.25, None).spp, 2);
}

fn pilot(mean: f32, variance: f32, pixels: usize, cost: f64) -> Pilot {
    Pilot {
        candidate: Candidate::from(Strategy::default()),
        spp: 4,
        cost,
        seconds: 0.1,
        mean: vec![glam::Vec3::splat(mean); pixels],
        variance: vec![glam::Vec3::splat(variance); pixels],
        caustic: 0.0,
        indirect: 0.0,
    }
}

/// Every pilot's relMSE is measured against one denominator, from the pilots' images weighed by
/// the inverse of their mean variances: two pilots of a flat 8×8 image, one reading 1 and the
/// other 3 (variances 1e-6 and 4e-6: weights 0.8 and 0.2, a pooled mean of 1.4 everywhere, so
/// the blend and the box agree: `r² = 1.96`), give relMSEs `v/(r² + 0.01)` with the same `r²`,
/// and efficiencies `1/(relMSE × cost)`. A pilot that met a rare bright path in one pixel of a
/// hundred (mean 1 there with variance 0.06, nothing elsewhere, where the truth is 0.01, which the
/// other pilot reads precisely with variance 1e-8) has a mean variance of `0.06/100 = 6e-4`, so
/// its weight is `1e-8/6e-4 ≈ 1.7e-5` of the other's: the pooled mean is 0.01 to 1e-5 (its
/// variance ~1e-8, `λ ≈ 0.998`), `r² ≈ 1.0e-4`, and the rare pilot's relMSE is
/// `0.06/(1.0e-4 + 0.01)/100 = 5.94e-4 × 100 = 0.0594`, its error against the truth; against its
/// own image (a render's estimate: mean 1, `λ = 0.51`, box 0.111, `r² = 0.516`) it reads
/// `1.14e-3`, 52× lower.
#[test]
fn pilots_are_measured_against_one_denominator() {
    let rows = shared_denominator(8, &[pilot(1.0, 1e-6, 64, 2.0), pilot(3.0, 4e-6, 64, 5.0)]);
    let r2 = 1.96 + 0.01;
    for (r, (v, cost)) in rows.iter().zip([(1e-6, 2.0), (4e-6, 5.0)]) {
        assert!((r.rel_mse / (v / r2) - 1.0).abs() < 1e-4, "{}", r.rel_mse);
        assert!((r.efficiency * r.rel_mse * cost - 1.0).abs() < 1e-9);
        assert!(r.rel_mse_se < 1e-3 * r.rel_mse, "a flat image: no spread");
    }
    // the rare bright path, in pixel 45 of a 10×10 image (away from the edges)
    let mut rare = pilot(0.0, 0.0, 100, 1.0);
    (rare.mean[45], rare.variance[45]) = (glam::Vec3::ONE, glam::Vec3::splat(0.06));
    let (mean, variance) = (rare.mean.clone(), rare.variance.clone());
    let rows = shared_denominator(10, &[rare, pilot(0.01, 1e-8, 100, 1.0)]);
    let own = crate::estimate::image_error(10, &mean, &variance).1;
    assert!((own / 1.140e-3 - 1.0).abs() < 1e-3, "{own}");
    let shared = rows[0].rel_mse;
    let truth = 0.06 / (0.01f64 * 0.01 + 0.01) / 100.0;
    assert!(
        (shared / truth - 1.0).abs() < 5e-3,
        "{shared} against {truth}"
    );
}

#[test]
fn a_guided_twin_differs_in_its_directions_alone() {
    let twin = |s: &str| Candidate::parse(s).unwrap().guided().to_string();
    assert_eq!(twin("mis"), "stratified+guided+mis");
    assert_eq!(twin("mis+reuse4"), "stratified+guided+mis+reuse4");
    assert_eq!(twin("mis+ears"), "stratified+guided+mis+ears");
    assert_eq!(twin("stratified+guided+mis"), "stratified+guided+mis");
    let d = default_candidates();
    assert_eq!([d[0].guided(), d[1].guided()], [d[2], d[3]]);
}
