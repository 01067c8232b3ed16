//! Unit tests of `--strategy auto`'s rule, names and pilot sizes.

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
    assert_eq!((d[0].reuse, d[1].reuse), (1, AUTO_REUSE));
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
