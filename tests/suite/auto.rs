//! `--strategy auto` (issue 51): the pilots choose by efficiency, the image is the chosen
//! strategy's own render (so it is unbiased whichever is chosen, and the pilots' samples are not
//! in it; a guided candidate's with the guide its pilot learned), the choice and the image do
//! not depend on the thread count, and contradictory flags are refused.

use crate::common;
use vrpt::commands::parse_flags;
use vrpt::commands::render::{RenderOutcome, RenderRequest};
use vrpt::render::NoProgress;

fn render(args: &[&str]) -> RenderOutcome {
    render_scene(&common::cornell_path(), args)
}

fn render_scene(scene: &std::path::Path, args: &[&str]) -> RenderOutcome {
    let mut all = vec![scene.to_str().unwrap()];
    all.extend_from_slice(args);
    let flags: Vec<String> = all.iter().map(|s| s.to_string()).collect();
    let request = parse_flags::<RenderRequest>("render", &flags).unwrap();
    request
        .prepare_in_memory()
        .unwrap()
        .run(&NoProgress)
        .unwrap()
}

/// Between the naive baseline (independent points, uniform directions, BSDF sampling only) and
/// MIS, whose MSE on the Cornell box is about 100× lower at equal spp (the lecture notebook's
/// compare), the pilots choose MIS whichever candidate comes first and whatever the seed. At 4
/// spp per pilot the baseline's rare hits of the light are mostly missed, so its pilot reads
/// only about 5–6× less efficient (z 7–10 with relMSE standard errors of 10–20% on 48×36 pixels):
/// the switch needs z > 2, a ratio above 1.3. The image is then `--strategy mis`'s with the
/// same seed, bit for bit: the pilots' samples are not in it; its recorded wall time is the
/// pilots' and the render's.
#[test]
fn auto_chooses_the_efficient_strategy_and_renders_it_as_itself() {
    let size = ["--width", "48", "--height", "36", "--spp", "64"];
    for base in [1u64, 2, 3] {
        let seed = common::seed(base).to_string();
        let mis = render(&[&size[..], &["--seed", &seed, "--strategy", "mis"]].concat());
        for candidates in ["independent,mis", "mis,independent"] {
            let args = [
                "--seed",
                &seed,
                "--strategy",
                "auto",
                "--auto-candidates",
                candidates,
            ];
            let auto = render(&[&size[..], &args].concat());
            let choice = auto.auto.as_ref().expect("the pilots' choice");
            assert_eq!(choice.candidate.to_string(), "mis", "{}", choice.table());
            assert_eq!(choice.rows.len(), 2);
            assert!(choice.rows.iter().all(|r| r.spp == 4));
            assert_eq!(auto.film.mean_image(), mis.film.mean_image(), "seed {seed}");
            assert_eq!(auto.meta.strategy, mis.meta.strategy);
            let record = auto.meta.auto.as_deref().unwrap();
            assert!(record.starts_with("chose mis;"), "{record}");
            // the metadata's wall time holds the pilots' too
            let total = (auto.stats.elapsed + choice.elapsed).as_secs_f64();
            assert!((auto.meta.render_seconds - total).abs() < 1e-9);
            assert!(auto.summary.contains("<- chosen"), "{}", auto.summary);
        }
    }
}

/// Under a time limit the pilots' costs are wall seconds: a probe of the first candidate sets
/// the pilots' spp from the time limit, then every candidate's pilot renders that spp (the
/// probe is not reused as the first one's pilot: it pays the process's warm-up). The contrast of
/// the test above (MIS about 5–6× as efficient as the naive baseline by its pilots, where wall
/// times vary by tens of percent at most) decides it whatever the timing noise, and the render
/// is then MIS's within what the pilots left of the limit.
#[test]
fn auto_under_a_time_limit_chooses_by_wall_time() {
    let size = ["--width", "48", "--height", "36", "--spp", "64"];
    for base in [1u64, 2] {
        let seed = common::seed(base).to_string();
        let args = [
            "--seed",
            &seed,
            "--strategy",
            "auto",
            "--auto-candidates",
            "independent,mis",
            "--time-limit",
            "30",
        ];
        let auto = render(&[&size[..], &args].concat());
        let choice = auto.auto.as_ref().expect("the pilots' choice");
        assert_eq!(choice.candidate.to_string(), "mis", "{}", choice.table());
        assert!(choice.table().contains("seconds"), "{}", choice.table());
        let spp = choice.rows[0].spp;
        assert!(spp >= 4 && spp.is_multiple_of(4), "{}", choice.table());
        assert!(choice.rows.iter().all(|r| r.spp == spp && r.cost > 0.0));
        assert!(auto.meta.auto.as_deref().unwrap().ends_with("cost seconds"));
        assert_eq!(auto.meta.strategy, vrpt::strategy::Strategy::default());
    }
}

/// A guided candidate is piloted (its guide trained) only where an unguided candidate beat the
/// first: with `mis` first, `independent` never does (MIS is 5–6× as efficient by the pilots,
/// above), so the guided candidate is not piloted, the table and the metadata say so, and mis
/// renders; with `independent` first, mis beats it (z 7–10), so the guided candidate is piloted
/// too, after the unguided ones. The default candidates are mis, path reuse, and both with
/// guided directions, the guided one last.
#[test]
fn auto_pilots_a_guided_candidate_only_where_an_unguided_one_won() {
    let size = ["--width", "48", "--height", "36", "--spp", "64"];
    let guided = "stratified+guided+mis";
    for base in [1u64, 2] {
        let seed = common::seed(40 + base).to_string();
        let args = ["--seed", &seed, "--strategy", "auto", "--auto-candidates"];
        let kept = render(&[&size[..], &args, &[&format!("mis,independent,{guided}")]].concat());
        let choice = kept.auto.as_ref().expect("the pilots' choice");
        assert_eq!(choice.candidate.to_string(), "mis", "{}", choice.table());
        assert_eq!(choice.rows.len(), 2, "{}", choice.table());
        assert_eq!(choice.unpiloted.len(), 1);
        assert_eq!(choice.unpiloted[0].to_string(), guided);
        assert!(choice.guide.is_none());
        assert!(choice.table().contains(&format!("{guided}: not piloted")));
        // no mirror or glass, no caustic: the other gate stays shut too
        assert_eq!(choice.caustic, 0.0);
        assert!(choice.table().contains("0% of mis's light caustic"));
        let record = kept.meta.auto.as_deref().unwrap();
        assert!(
            record.contains(&format!("(not piloted: {guided})")),
            "{record}"
        );
        let switched =
            render(&[&size[..], &args, &[&format!("independent,mis,{guided}")]].concat());
        let choice = switched.auto.as_ref().expect("the pilots' choice");
        let names: Vec<String> = (choice.rows.iter())
            .map(|r| r.candidate.to_string())
            .collect();
        assert_eq!(names, ["independent", "mis", guided], "{}", choice.table());
        assert!(choice.unpiloted.is_empty());
        assert_ne!(choice.candidate.to_string(), "independent");
    }
    let d: Vec<String> = (vrpt::render::auto::default_candidates().iter())
        .map(|c| c.to_string())
        .collect();
    assert_eq!(d, ["mis", "mis+reuse4", "stratified+guided+mis+reuse4"]);
}

/// Light a path finds through a mirror or glass after a Phong vertex is counted as caustic
/// (what opens auto's guided pilots, [`CAUSTIC_GATE`]): none at all on the Cornell box (no
/// mirror or glass); all of it where the camera sees only the lamp scene's floor, lit through the
/// glass shade around its lamp (every light path ends floor, …, glass, lamp: the luminance summed
/// per emission found equals the luminance summed per path but for f32 rounding, ~1e-7 per
/// path); and from the lamp scene's own camera a part, at least the gate's quarter (54% at 128²,
/// 16 spp; at 32² its noise is a few percent), and not all: that camera also sees the lamp
/// through the shade, which is no caustic (no Phong vertex before the glass).
#[test]
fn caustic_light_is_counted_where_it_comes_through_glass() {
    use vrpt::render::{auto::CAUSTIC_GATE, RenderSettings};
    use vrpt::scene::Scene;
    let rays = |scene: &Scene| {
        let settings = RenderSettings {
            width: 32,
            height: 32,
            spp: 16,
            max_depth: 12,
            seed: common::seed(7),
            ..RenderSettings::for_scene(scene)
        };
        common::render_quiet(scene, &settings).1.rays
    };
    let cornell = rays(&common::shipped("cornell-box"));
    assert!(cornell.light > 0.0);
    assert_eq!((cornell.caustic, cornell.caustic_share()), (0.0, 0.0));

    let lamp = rays(&common::shipped("lamp"));
    let share = lamp.caustic_share();
    assert!((CAUSTIC_GATE..0.9).contains(&share), "{share}");

    let dir = tempfile::tempdir().unwrap();
    for f in ["lamp.obj", "lamp.mtl"] {
        std::fs::copy(common::shipped_path("lamp").join(f), dir.path().join(f)).unwrap();
    }
    // straight down at the floor from below the shade: floor only
    let toml = "obj = \"lamp.obj\"\n[camera]\neye = [0, 1.5, 0.9]\ntarget = [0, 0, 0.9]\n\
                up = [0, 0, -1]\nfov = 20\n[environment]\nradiance = [0, 0, 0]\n";
    common::write(dir.path(), "scene.toml", toml);
    let floor = rays(&vrpt::scene::load(dir.path()).unwrap());
    assert!(floor.light > 0.0);
    assert!(
        (floor.caustic / floor.light - 1.0).abs() < 1e-5,
        "{floor:?}"
    );
}

/// Where a quarter or more of the first candidate's pilot's light is caustic ([`CAUSTIC_GATE`]),
/// the guided candidates are piloted even though no unguided one beat the first. The unguided
/// candidate besides mis is mis again, whose pilot is mis's own bit for bit (the same seeds), so
/// it cannot beat it (z = 0): on the Cornell box (no glass) the guided candidate is then not
/// piloted, and on the lamp behind its glass shade it is, the caustics its only reason, and the
/// table and the metadata say so. (`independent` would not do as the other: on the lamp, where
/// no light sample gets through the shade, its BSDF-only paths read 2.5× as efficient as mis.)
#[test]
fn auto_pilots_a_guided_candidate_where_the_light_is_caustic() {
    use vrpt::render::auto::CAUSTIC_GATE;
    let guided = "stratified+guided+mis";
    let size = ["--width", "32", "--height", "32", "--spp", "64"];
    let seed = common::seed(43).to_string();
    let args = ["--seed", &seed, "--strategy", "auto", "--auto-candidates"];
    let list = format!("mis,mis,{guided}");
    let run = |scene: &std::path::Path| {
        let out = render_scene(scene, &[&size[..], &args, &[&list]].concat());
        let choice = out.auto.clone().expect("the pilots' choice");
        let record = out.meta.auto.clone().unwrap();
        (choice, record)
    };
    let (cornell, record) = run(&common::cornell_path());
    assert_eq!(cornell.caustic, 0.0);
    assert_eq!(cornell.z, 0.0, "{}", cornell.table());
    assert_eq!(cornell.unpiloted.len(), 1, "{}", cornell.table());
    assert!(
        record.contains(&format!("(not piloted: {guided})")),
        "{record}"
    );

    let (lamp, record) = run(&common::shipped_path("lamp"));
    let names: Vec<String> = (lamp.rows.iter())
        .map(|r| r.candidate.to_string())
        .collect();
    assert_eq!(names, ["mis", "mis", guided], "{}", lamp.table());
    let same = |r: &vrpt::render::auto::PilotRow| (r.rel_mse, r.rel_mse_se, r.cost);
    assert_eq!(same(&lamp.rows[0]), same(&lamp.rows[1]));
    assert!(lamp.unpiloted.is_empty());
    assert!(lamp.caustic >= CAUSTIC_GATE, "{}", lamp.table());
    assert!(
        lamp.table().contains("guided candidates piloted: "),
        "{}",
        lamp.table()
    );
    assert!(
        record.contains("; caustic ") && !record.contains("; caustic 0.0"),
        "{record}"
    );
}

/// Path reuse as a candidate: whichever the pilots choose, the image is that candidate's own
/// render (`--strategy mis --reuse 4` for `mis+reuse4`, bit for bit), and the metadata says
/// which reuse rendered it. With reuse first it stays: on the Cornell box it is the more
/// efficient (1.2–3.0× by the pilots at 48×36 to 128×96), so mis would need z > 2 the wrong way.
#[test]
fn auto_chooses_path_reuse_and_renders_it_as_itself() {
    let size = ["--width", "48", "--height", "36", "--spp", "64"];
    for base in [1u64, 2] {
        let seed = common::seed(base).to_string();
        for candidates in ["mis+reuse4,mis", "mis,mis+reuse4"] {
            let args = ["--seed", &seed, "--strategy", "auto"];
            let auto = render(&[&size[..], &args, &["--auto-candidates", candidates]].concat());
            let choice = auto.auto.as_ref().expect("the pilots' choice");
            if candidates.starts_with("mis+reuse4") {
                assert_eq!(choice.candidate.reuse, 4, "{}", choice.table());
            }
            let k = choice.candidate.reuse.to_string();
            let flags = ["--seed", &seed, "--strategy", "mis", "--reuse", &k];
            let own = render(&[&size[..], &flags].concat());
            assert_eq!(auto.film.mean_image(), own.film.mean_image(), "seed {seed}");
            assert_eq!(auto.meta.reuse, own.meta.reuse);
            assert_eq!(auto.settings.reuse, choice.candidate.reuse);
            let record = auto.meta.auto.as_deref().unwrap();
            assert!(record.starts_with(&format!("chose {};", choice.candidate)));
            assert!(record.contains("mis+reuse4 "), "{record}");
        }
    }
}

/// EARS as a candidate (`+ears`): chosen, the image is its own render (`--strategy mis
/// --roulette ears`, bit for bit: its cache is trained again from the render's seed, not kept
/// from its pilot) and the metadata says which roulette rendered it. Against the naive
/// baseline (`independent`) its pilot reads 9–10× more efficient at 16 spp on 48×36 pixels
/// (6–8× when each pilot was its own denominator, z 17–24 over four seeds; its training and the
/// EARS ray weight counted), so it is chosen in either order.
#[test]
fn auto_chooses_ears_and_renders_it_as_itself() {
    use vrpt::integrator::rrs::Roulette;
    let size = ["--width", "48", "--height", "36", "--spp", "256"];
    for (base, candidates) in [(1u64, "mis+ears,independent"), (2, "independent,mis+ears")] {
        let seed = common::seed(base).to_string();
        let args = ["--seed", &seed, "--strategy", "auto"];
        let auto = render(&[&size[..], &args, &["--auto-candidates", candidates]].concat());
        let choice = auto.auto.as_ref().expect("the pilots' choice");
        assert_eq!(
            choice.candidate.to_string(),
            "mis+ears",
            "{}",
            choice.table()
        );
        assert!(choice.table().contains("an EARS ray counts"));
        let flags = ["--seed", &seed, "--strategy", "mis", "--roulette", "ears"];
        let own = render(&[&size[..], &flags].concat());
        assert_eq!(auto.film.mean_image(), own.film.mean_image(), "seed {seed}");
        assert_eq!(auto.meta.roulette, Roulette::Ears);
        assert_eq!(auto.settings.roulette, Roulette::Ears);
        let record = auto.meta.auto.as_deref().unwrap();
        assert!(record.starts_with("chose mis+ears;"), "{record}");
    }
}

/// With rays as the cost the pilots are deterministic: the same choice, the same pilot numbers
/// and the same image on 1 and 2 threads (the default candidates, path reuse among them, whose
/// connections are counted in the cost); on a small image whose pilots render it whole, and on
/// one whose pilots render a quarter of its tiles (128×96: 12 of 48).
#[test]
fn auto_does_not_depend_on_the_thread_count() {
    for (size, tiles) in [
        (["32", "24", "32"], (4, 4)),
        (["128", "96", "16"], (12, 48)),
    ] {
        let [w, h, spp] = size;
        let args = [
            "--width",
            w,
            "--height",
            h,
            "--spp",
            spp,
            "--strategy",
            "auto",
        ];
        let one = render(&[&args[..], &["--threads", "1"]].concat());
        let two = render(&[&args[..], &["--threads", "2"]].concat());
        let (a, b) = (one.auto.unwrap(), two.auto.unwrap());
        assert_eq!(a.tiles, tiles);
        assert!(a
            .record()
            .contains(&format!("on {} of {} tiles", tiles.0, tiles.1)));
        assert_eq!(a.candidate, b.candidate);
        for (x, y) in a.rows.iter().zip(&b.rows) {
            assert_eq!((x.rel_mse, x.cost), (y.rel_mse, y.cost));
        }
        assert_eq!(one.film.mean_image(), two.film.mean_image());
    }
}

#[test]
fn auto_refuses_what_it_cannot_honour() {
    let cornell = common::cornell_path();
    let scene = cornell.to_str().unwrap();
    let out = |extra: &[&str]| {
        let mut args = vec![
            "render",
            scene,
            "--spp",
            "4",
            "-o",
            "/tmp/vrpt-auto-refused.png",
        ];
        args.extend_from_slice(extra);
        common::vrpt(&args)
    };
    let cases: [(&[&str], &str); 10] = [
        (&["--strategy", "auto", "--sampler", "sobol"], "--sampler"),
        (&["--strategy", "auto", "--shard", "0/2"], "--shard"),
        (&["--strategy", "auto", "--adaptive"], "--adaptive"),
        (&["--auto-candidates", "mis"], "only --strategy auto"),
        (&["--strategy", "auto", "--reuse", "2"], "mis+reuse2"),
        (&["--strategy", "auto", "--roulette", "ears"], "mis+ears"),
        (
            &["--strategy", "auto", "--roulette", "classic"],
            "--roulette classic",
        ),
        (
            &[
                "--strategy",
                "auto",
                "--auto-candidates",
                "mis,mis+reuse2+ears",
            ],
            "does not combine",
        ),
        (
            &["--strategy", "auto", "--auto-candidates", "mis,mis+reuse9"],
            "+reuseK",
        ),
        (
            &["--strategy", "auto", "--auto-candidates", "nonsense"],
            "nonsense",
        ),
    ];
    for (extra, expect) in cases {
        common::assert_refused(&out(extra), &extra.join(" "), &[expect]);
    }
    let guide = common::vrpt(&["guide", scene, "--pixel", "10,10", "--strategy", "auto"]);
    common::assert_refused(&guide, "guide --strategy auto", &["only vrpt render"]);
}

/// `Entry::auto` in an experiment: a row named "auto" whose runs are the chosen strategy's
/// renders (here MIS over the baseline, so its MSE is MIS's order, far below the baseline's),
/// and whose time includes the pilots'.
#[test]
fn auto_is_an_entry_of_experiments() {
    use vrpt::analysis::experiments::{compare_entries, Entry};
    use vrpt::strategy::Strategy;
    let scene = common::shipped("cornell-box");
    let reference_settings = vrpt::render::RenderSettings {
        width: 24,
        height: 24,
        spp: 1024,
        seed: common::seed(900),
        ..Default::default()
    };
    let reference = common::as_image(&scene, &reference_settings);
    let mut settings = common::experiment_settings(24, 24, 8, 3);
    settings.reference_seeds = vec![reference_settings.seed];
    let baseline = Strategy::parse("independent").unwrap();
    let entries = [
        Entry::builtin(baseline),
        Entry::auto(vec![baseline.into(), Strategy::default().into()]),
    ];
    let c = compare_entries(
        &scene,
        &reference,
        &entries,
        16,
        None,
        &settings,
        &NoProgress,
    )
    .unwrap();
    assert_eq!(c.rows[1].strategy, "auto");
    assert!(c.rows[1].mse * 10.0 < c.rows[0].mse, "{}", c.table());
    assert!(c.rows.iter().all(|r| r.seconds > 0.0));
}

/// A guided candidate learns its guide on the pilots' strip and, chosen, hands it to the
/// render: the image is the guided render with that guide (bit for bit the render given it,
/// [`PassPlan::guide`]), not `--directions guided`'s own (whose guide trains on the whole image
/// with the render's budget), and the same on 1 and 2 threads. The guide trained within
/// [`GUIDE_SHARE`] of the render's samples per pixel of the strip (128×96: a quarter of the
/// tiles, so `256 / 8 · 4 = 128` spp: iterations 1 + 2 + … + 64 = 127), and the render reports
/// that training as its own. A candidate list of one keeps it whatever the pilots read; the
/// table names the weight of a guided ray ([`GUIDED_RAY_COST`]).
#[test]
fn auto_hands_its_guided_pilots_guide_to_the_render() {
    use vrpt::render::auto::GUIDED_RAY_COST;
    use vrpt::render::{render_passes, PassPlan};
    let size = ["--width", "128", "--height", "96", "--spp", "256"];
    let seed = common::seed(31).to_string();
    let args = ["--seed", &seed, "--max-depth", "5", "--strategy", "auto"];
    let guided = ["--auto-candidates", "stratified+guided+mis"];
    let auto = render(&[&size[..], &args, &guided, &["--threads", "2"]].concat());
    let choice = auto.auto.as_ref().expect("the pilots' choice");
    assert_eq!(choice.candidate.to_string(), guided[1]);
    let learned = choice.guide.clone().expect("the guided pilot's guide");
    assert_eq!(
        (learned.stats.iterations, learned.stats.training_spp),
        (7, 127)
    );
    let g = auto.stats.guide.expect("the render's guide stats");
    assert_eq!((g.iterations, g.training_spp), (7, 127));
    assert!(choice
        .table()
        .contains(&format!("a guided ray counts {GUIDED_RAY_COST}")));
    let scene = common::shipped("cornell-box");
    let plan = PassPlan {
        guide: Some(learned),
        ..PassPlan::default()
    };
    let handed = render_passes(&scene, &auto.settings, &plan, &NoProgress).unwrap();
    assert_eq!(auto.film.mean_image(), handed.film.mean_image());
    let one = render(&[&size[..], &args, &guided, &["--threads", "1"]].concat());
    assert_eq!(one.film.mean_image(), auto.film.mean_image());
    let flags = [
        "--seed",
        &seed,
        "--max-depth",
        "5",
        "--directions",
        "guided",
    ];
    let own = render(&[&size[..], &flags].concat());
    assert_ne!(auto.film.mean_image(), own.film.mean_image());
    assert_eq!(auto.settings.strategy, own.settings.strategy);
}
