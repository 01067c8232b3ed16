//! The `vrpt` binary end to end: a small Cornell box render to PNG and EXR, and one clear error
//! line with a non-zero exit (never a panic) for each kind of bad input.

use crate::common;
use common::{assert_one_line_error, ok, vrpt};

use std::path::{Path, PathBuf};

#[test]
fn renders_the_cornell_box_to_png_and_exr() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("cb.png");
    let scene = common::cornell_path().join("cornell-box.obj");
    let out = vrpt(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "24",
        "--spp",
        "16",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("Mrays/s") && stderr.contains("samples/s"),
        "{stderr}"
    );
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (32, 24));
    // the light is in view (white), the box is not black
    assert!(img.pixels().any(|p| p.0.iter().all(|&c| c == 255)));
    // the classic view: the red wall on the left, the green wall on the right
    let redness = |x0: u32, x1: u32| {
        let mut s = 0.0f64;
        for y in 0..24 {
            for x in x0..x1 {
                let p = img.get_pixel(x, y).0;
                s += p[0] as f64 - p[1] as f64;
            }
        }
        s
    };
    assert!(
        redness(0, 6) > 0.0 && redness(26, 32) < 0.0,
        "{} {}",
        redness(0, 6),
        redness(26, 32)
    );

    let exr = dir.path().join("cb.exr");
    let var = dir.path().join("var.exr");
    let out = vrpt(&[
        "render",
        common::cornell_path().to_str().unwrap(),
        "-o",
        exr.to_str().unwrap(),
        "--variance",
        var.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "9",
        "--seed",
        "5",
        "--max-depth",
        "3",
        "--strategy",
        "importance",
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stderr.is_empty(), "--quiet prints nothing");
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (16, 16));
    let m = &img.metadata;
    assert_eq!(m["spp"], "9");
    assert_eq!(m["seed"], "5");
    assert_eq!(m["max_depth"], "3");
    assert_eq!(m["sampler"], "independent");
    assert_eq!(m["directions"], "phong");
    assert_eq!(m["strategy"], "importance");
    assert!(m["scene"].ends_with("cornell-box.obj"));
    assert!(m["render_seconds"].parse::<f64>().unwrap() > 0.0);
    let v = vrpt::image_io::read_exr(&var).unwrap();
    assert!(v.pixels.iter().all(|p| p.min_element() >= 0.0));
    assert!(v.pixels.iter().any(|p| p.max_element() > 0.0));
}

#[test]
fn bad_input_gives_one_line_and_nonzero_exit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cb = common::cornell_path();
    let cb = cb.to_str().unwrap();
    let bad_obj = common::write(d, "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 oops\nf 1 2 3\n");
    let out_png = d.join("x.png");
    let o = out_png.to_str().unwrap();

    let missing = d.join("missing.obj");
    assert_one_line_error(
        &vrpt(&["render", missing.to_str().unwrap(), "-o", o]),
        "missing",
        "not found",
    );
    assert_one_line_error(
        &vrpt(&["render", bad_obj.to_str().unwrap(), "-o", o]),
        "malformed",
        "line 3",
    );
    assert_one_line_error(
        &vrpt(&["render", cb, "-o", o, "--spp", "abc"]),
        "spp abc",
        "--spp",
    );
    assert_one_line_error(
        &vrpt(&["render", cb, "-o", o, "--spp", "0"]),
        "spp 0",
        "--spp",
    );
    if cfg!(target_os = "linux") {
        // 65536² pixels need ~640 GiB: refused before any buffer is allocated (an allocation
        // failure would abort with no error line)
        assert_one_line_error(
            &vrpt(&[
                "render", cb, "-o", o, "--width", "65536", "--height", "65536",
            ]),
            "65536x65536",
            "needs about",
        );
    }
    assert_one_line_error(
        &vrpt(&["render", cb, "-o", o, "--sampler", "halton"]),
        "sampler",
        "halton",
    );
    assert_one_line_error(
        &vrpt(&["render", cb, "-o", o, "--bogus"]),
        "unknown flag",
        "--bogus",
    );
    assert_one_line_error(
        &vrpt(&[
            "render",
            cb,
            "-o",
            o,
            "--strategy",
            "importance",
            "--directions",
            "uniform",
        ]),
        "conflicting strategy",
        "--strategy importance",
    );
    assert_one_line_error(
        &vrpt(&[
            "render",
            cb,
            "-o",
            o,
            "--strategy",
            "combined",
            "--lights",
            "mis",
        ]),
        "conflicting lights",
        "--strategy combined uses --lights bsdf",
    );
    assert_one_line_error(
        &vrpt(&["render", cb, "-o", o, "--lights", "sometimes"]),
        "lights value",
        "sometimes",
    );
    assert_one_line_error(
        &vrpt(&["render", cb, "-o", "/nonexistent-dir/x.png", "--spp", "1"]),
        "unwritable",
        "/nonexistent-dir",
    );
    let txt = d.join("x.txt");
    assert_one_line_error(
        &vrpt(&["render", cb, "-o", txt.to_str().unwrap()]),
        "format",
        ".exr or .png",
    );
    assert!(!Path::new(o).exists(), "no output on failure");
}

#[test]
fn a_failed_run_leaves_the_previous_image_intact() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("keep.png");
    std::fs::write(&png, b"previous image").unwrap();
    let bad_obj = common::write(dir.path(), "bad.obj", "v 0 0 0\nf 1 2 3\n");
    let out = vrpt(&[
        "render",
        bad_obj.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert_eq!(std::fs::read(&png).unwrap(), b"previous image");
    // no temporary files are left behind
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(
        names.iter().all(|n| !n.to_string_lossy().ends_with(".tmp")),
        "{names:?}"
    );
}

#[test]
fn help_explains_the_flags() {
    let out = vrpt(&["render", "--help"]);
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    for flag in [
        "--spp",
        "--width",
        "--height",
        "--max-depth",
        "--seed",
        "--threads",
        "--quiet",
        "--sampler",
        "--directions",
        "--strategy",
        "--lights",
        "--exposure",
        "--variance",
    ] {
        assert!(s.contains(flag), "help lacks {flag}");
    }
    assert!(
        s.contains("square spp"),
        "help says square spp stratify best"
    );
}

/// The metadata of a 16×16 render of the Cornell box asking for 10⁸ spp in passes of 4, with
/// `extra` flags (a time limit among them: 10⁸ spp would take hours).
fn time_limited_render(extra: &[&str]) -> vrpt::output::RenderMetadata {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("t.exr");
    let (cornell, out_path) = (common::cornell_path(), exr.to_str().unwrap().to_string());
    let mut args = vec![
        "render",
        cornell.to_str().unwrap(),
        "-o",
        &out_path,
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "100000000",
        "--pass-spp",
        "4",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let out = vrpt(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    vrpt::output::RenderMetadata::from_attributes(&img.metadata).unwrap()
}

/// `--time-limit`: the render stops at the first whole pass after the limit, and the image
/// records the spp it reached (at least the first pass, far below the --spp cap) and the
/// limit.
#[test]
fn time_limited_render_stops_at_a_whole_pass() {
    let m = time_limited_render(&["--time-limit", "0.3"]);
    // the first pass is 4 spp; the next ones double or take what the time left allows
    assert!(m.spp >= 4, "spp {}", m.spp);
    // 10⁸ spp of 256 pixels would take hours: the limit stopped it
    assert!(m.spp < 100_000_000, "spp {}", m.spp);
    assert_eq!(m.pass_spp, Some(4));
    assert_eq!(m.time_limit_seconds, Some(0.3));
    assert!(m.render_seconds >= 0.3, "{}", m.render_seconds);
    // every pass is recorded (issue 46: only the first was), and they add up to the spp
    assert_eq!(m.passes.first(), Some(&4));
    assert_eq!(m.passes.iter().map(|&p| p as u64).sum::<u64>(), m.spp);
}

/// A growing render that reaches its `--spp` keeps every pass off a sliver of a grid, the one
/// the spp cuts included (issue 46: `--spp 997 --time-limit 60` ended in a pass of 501 =
/// 3·167), and records its passes; a render whose replicates did not all render records and
/// says how many did.
#[test]
fn growing_passes_and_replicates_are_recorded_as_rendered() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("g.exr");
    let scene = common::cornell_path();
    let (s, e) = (scene.to_str().unwrap(), exr.to_str().unwrap());
    let small = ["--width", "4", "--height", "4", "-o", e];
    let mut args = vec!["render", s, "--spp", "997", "--time-limit", "60", "-q"];
    args.extend(small);
    ok(vrpt(&args));
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    let m = vrpt::output::RenderMetadata::from_attributes(&img.metadata).unwrap();
    assert_eq!(m.spp, 997);
    assert_eq!(m.passes.iter().sum::<u32>(), 997, "{:?}", m.passes);
    let (_, body) = m.passes.split_last().unwrap();
    for &p in body {
        assert_eq!(
            vrpt::sampler::stratifiable(p as u64),
            p as u64,
            "{:?}",
            m.passes
        );
    }
    let mut args = vec![
        "render",
        s,
        "--spp",
        "64",
        "--pass-spp",
        "64",
        "--replicates",
        "4",
    ];
    args.extend(small);
    let out = ok(vrpt(&args));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("only 1 of the 4 replicates rendered"),
        "{stderr}"
    );
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    let m = vrpt::output::RenderMetadata::from_attributes(&img.metadata).unwrap();
    assert_eq!(m.estimate.unwrap().replicates, 1);
}

/// `--adaptive --time-limit`: rounds follow the clock, doubling while the time left allows, so
/// their number grows as the logarithm of the samples, not in proportion (rounds of a fixed
/// pass, as before, took `spp/R` of them: 1 spp per replicate each here). With first round 1
/// spp per replicate and doubling, `r` rounds plan at least `2^(r−k) − 1` spp per replicate
/// when the last `k` rounds were cut to the time left; a round cut to the time left is one of
/// the last few (it ends about when the time does), so `r ≤ log2(spp/R) + 4` whatever the
/// machine's speed.
#[test]
fn time_limited_adaptive_rounds_follow_the_clock() {
    let m = time_limited_render(&["--adaptive", "--time-limit", "1"]);
    let rounds = m
        .adaptive_rounds
        .expect("an adaptive render says its rounds");
    let per_replicate = m.spp as f64 / 4.0;
    assert!(
        (rounds as f64) <= per_replicate.log2() + 4.0,
        "{rounds} rounds for {per_replicate} spp per replicate"
    );
    assert!(m.spp < 100_000_000, "spp {}", m.spp);
}

/// An EXR whose metadata claims another size than its pixels is refused by `merge` and `diff`
/// with one line, never indexed by the claimed size.
#[test]
fn images_whose_metadata_lies_about_their_size_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.exr");
    let out = vrpt(&[
        "render",
        common::cornell_path().to_str().unwrap(),
        "-o",
        a.to_str().unwrap(),
        "--width",
        "4",
        "--height",
        "4",
        "--spp",
        "2",
        "-q",
    ]);
    assert!(out.status.success());
    let img = vrpt::image_io::read_exr(&a).unwrap();
    let mut meta = img.metadata.clone();
    meta.insert("width".into(), "64".into());
    meta.insert("first_sample".into(), "2".into());
    let b = dir.path().join("b.exr");
    vrpt::image_io::write_exr(
        &b,
        &vrpt::image_io::RgbImage {
            metadata: meta,
            ..img.clone()
        },
    )
    .unwrap();
    let m = dir.path().join("m.exr");
    assert_one_line_error(
        &vrpt(&[
            "merge",
            a.to_str().unwrap(),
            b.to_str().unwrap(),
            "-o",
            m.to_str().unwrap(),
        ]),
        "merge",
        "64×4",
    );
    assert_one_line_error(
        &vrpt(&["diff", b.to_str().unwrap(), a.to_str().unwrap()]),
        "diff",
        "64×4",
    );
    let (a_, b_) = (a.to_str().unwrap(), b.to_str().unwrap());
    assert_one_line_error(
        &vrpt(&["diff", a_, a_, "--pair-denominator", b_]),
        "diff --pair-denominator",
        "64×4",
    );
    assert!(!m.exists());
}

/// `--stats` reports where the time went (load, BVH build, the traced share of the thread
/// time, each a number in range) and leaves the image bit-identical: timing draws no random
/// numbers and changes no decision.
#[test]
fn stats_report_the_time_split_and_change_no_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::cornell_path().join("cornell-box.obj");
    let render = |name: &str, extra: &[&str]| {
        let exr = dir.path().join(name);
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "-o",
            exr.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "16",
        ];
        args.extend_from_slice(extra);
        let out = vrpt(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        (exr, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (a, plain) = render("plain.exr", &[]);
    let (b, timed) = render("timed.exr", &["--stats"]);
    assert!(!plain.contains("time:"), "{plain}");
    let line = timed
        .lines()
        .find(|l| l.starts_with("time: scene load"))
        .unwrap_or_else(|| panic!("no time line: {timed}"));
    let percent = |key: &str| -> f64 {
        let rest = &line[line.find(key).unwrap_or_else(|| panic!("{key}: {line}")) + key.len()..];
        rest.split('%').next().unwrap().trim().parse().unwrap()
    };
    let (trace, shade) = (percent("trace "), percent("shade and sample "));
    assert!(trace > 0.0 && trace < 100.0, "{line}");
    assert!((trace + shade - 100.0).abs() < 0.15, "{line}");
    assert!(
        line.contains("BVH build") && line.contains("thread-seconds"),
        "{line}"
    );
    // the cost model: every phase named with its ns per sample; traversal and shadow rays,
    // which every path of the lit box has, cost something; the phases sum to at most the
    // thread time per sample (what is over it is the clock's, taken out)
    let cost = timed
        .lines()
        .find(|l| l.starts_with("cost per sample, ns ("))
        .unwrap_or_else(|| panic!("no cost line: {timed}"));
    let number_after = |key: &str| -> f64 {
        let rest = &cost[cost.find(key).unwrap_or_else(|| panic!("{key}: {cost}")) + key.len()..];
        let end = rest
            .find(|c: char| !c.is_ascii_digit())
            .unwrap_or(rest.len());
        rest[..end]
            .parse()
            .unwrap_or_else(|_| panic!("{key}: {cost}"))
    };
    let phases = vrpt::integrator::PHASE_NAMES.map(|p| number_after(&format!(" {p} ")));
    let per_sample = number_after("; ");
    assert!(phases[1] > 0.0 && phases[5] > 0.0, "{cost}");
    let sum: f64 = phases.iter().sum();
    // each printed number is rounded to 1 ns
    assert!(sum <= per_sample + 8.0, "{sum} > {per_sample}: {cost}");
    let read = |p: &Path| {
        exr::prelude::read_first_rgba_layer_from_file(
            p,
            |r, _| vec![[0f32; 3]; r.width() * r.height()],
            |v: &mut Vec<[f32; 3]>, p, (r, g, b, _a): (f32, f32, f32, f32)| {
                v[p.y() * 32 + p.x()] = [r, g, b]
            },
        )
        .unwrap()
        .layer_data
        .channel_data
        .pixels
    };
    assert!(read(&a) == read(&b), "--stats changed the image");
}

/// A guided render says how its time split between training and the final iteration, how big
/// its tree grew and which training iterations its image combines, on `--stats` and in the
/// EXR's metadata (`--training-images discard`: none; refused without guided directions), and
/// what its gate read (`--guide-gate off`: nothing; refused without guided directions);
/// `vrpt guide` writes its map and refuses what it cannot show in one line.
#[test]
fn guided_renders_report_their_training_and_guide_shows_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::cornell_path();
    let exr = dir.path().join("g.exr");
    let out = vrpt(&[
        "render",
        scene.to_str().unwrap(),
        "--directions",
        "guided",
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "16",
        "--stats",
        "-o",
        exr.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("guiding: training 7 spp in 3 iterations"))
        .unwrap_or_else(|| panic!("no guiding line: {err}"));
    assert!(
        line.contains("spatial leaves") && line.contains("MiB"),
        "{line}"
    );
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    let meta = vrpt::output::RenderMetadata::require(&img, &exr).unwrap();
    let g = meta.guide.expect("guided metadata");
    assert_eq!((g.iterations, g.training_spp), (3, 7));
    assert!(g.leaves >= 1 && g.quad_nodes >= 1 && g.bytes > 0);
    assert!(g.training_seconds > 0.0 && g.final_seconds > 0.0);
    assert_eq!(meta.spp, 16);
    // iterations of 2 and 4 spp hold a variance to weigh by; the one of 1 spp does not
    assert!(
        err.contains(
            "the image combines the final iteration with 2 training images (2 iterations, 0 of \
             the gate's probes)"
        ),
        "{err}"
    );
    assert_eq!(g.combined, 2);
    assert!(g.final_weight > 0.0 && g.final_weight < 1.0, "{g:?}");
    assert_eq!(img.samples.as_ref().unwrap()[0], 16 + 2 + 4);
    let render = |extra: &[&str]| {
        let mut a = vec![
            "render",
            scene.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "16",
            "--stats",
            "-o",
            exr.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        vrpt(&a)
    };
    let out = render(&["--directions", "guided", "--training-images", "discard"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && !err.contains("combines"), "{err}");
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    let meta = vrpt::output::RenderMetadata::require(&img, &exr).unwrap();
    assert_eq!(
        meta.guide.map(|g| (g.combined, g.final_weight)),
        Some((0, 1.0))
    );
    assert_eq!(img.samples.as_ref().unwrap()[0], 16);
    assert_one_line_error(
        &render(&["--training-images", "keep"]),
        "training images without guiding",
        "only a guided render",
    );
    assert_one_line_error(
        &render(&[
            "--directions",
            "guided",
            "--reuse",
            "2",
            "--training-images",
            "keep",
        ]),
        "training images kept with path reuse",
        "final iteration alone",
    );
    assert_one_line_error(
        &render(&["--guide-gate", "on"]),
        "a gate without guiding",
        "only a guided render",
    );
    assert!(
        !render(&["--directions", "guided", "--guide-gate", "maybe"])
            .status
            .success()
    );
    // the gate (`render::gate`): at 64×64 and 128 spp the training's iterations of 32 and
    // 64 spp hold 2¹⁷ paths, so it reads at least one probe; `off` reads none
    let gated = |extra: &[&str]| {
        let mut a = vec!["render", scene.to_str().unwrap(), "--directions", "guided"];
        a.extend_from_slice(&["--width", "64", "--height", "64", "--spp", "128", "--stats"]);
        a.extend_from_slice(&["-o", exr.to_str().unwrap()]);
        a.extend_from_slice(extra);
        let out = vrpt(&a);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{err}");
        let img = vrpt::image_io::read_exr(&exr).unwrap();
        let meta = vrpt::output::RenderMetadata::require(&img, &exr).unwrap();
        (err, meta.guide_gate)
    };
    let (err, record) = gated(&[]);
    let record = record.expect("the gate's record in the metadata");
    assert!(
        (record.starts_with("closed at ") || record.starts_with("open"))
            && record.contains("as efficient as the guide, z "),
        "{record}"
    );
    assert!(err.contains(&format!("guiding: gate {record}")), "{err}");
    // at 16 spp the training (8 spp) ends before the first probe (2¹⁷ paths: 32 spp at
    // 64×64), and the record says the guide rendered unjudged
    let mut a = vec!["render", scene.to_str().unwrap(), "--directions", "guided"];
    a.extend_from_slice(&["--width", "64", "--height", "64", "--spp", "16", "--stats"]);
    a.extend_from_slice(&["-o", exr.to_str().unwrap()]);
    let out = vrpt(&a);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let meta =
        vrpt::output::RenderMetadata::require(&vrpt::image_io::read_exr(&exr).unwrap(), &exr)
            .unwrap();
    let unread = "unread (the training ended before its first probe, at 32 spp)";
    assert_eq!(meta.guide_gate.as_deref(), Some(unread));
    assert!(
        err.contains(&format!("guiding: gate {unread}; the guide kept")),
        "{err}"
    );
    let (err, record) = gated(&["--guide-gate", "off"]);
    assert!(record.is_none() && !err.contains("guiding: gate"), "{err}");
    // ungated, the training images are kept all the same
    assert!(
        err.contains("guiding: the image combines the final iteration with "),
        "{err}"
    );

    let png = dir.path().join("guide.png");
    let args = |extra: &[&str]| {
        let mut a = vec![
            "guide",
            scene.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "16",
            "--brute-spp",
            "2",
            "--map-width",
            "32",
            "-o",
            png.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        vrpt(&a)
    };
    let out = args(&["--pixel", "16,28"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("total variation distance"), "{text}");
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    assert_one_line_error(&args(&["--pixel", "40,2"]), "pixel outside", "outside");
    assert_one_line_error(&args(&["--pixel", "4"]), "pixel without y", "X,Y");
    assert_one_line_error(
        &args(&["--pixel", "4,4", "--directions", "phong"]),
        "not guided",
        "guided",
    );
}

/// A guided render under `--time-limit` spends its training and its final iteration inside the
/// limit's passes: it trains (iterations of 1, 2, 4, … spp, at least one), stops training on time
/// rather than at half of an absurd spp, and its recorded time includes the training.
#[test]
fn time_limited_guided_render_trains_inside_the_limit() {
    let m = time_limited_render(&["--time-limit", "0.5", "--directions", "guided"]);
    let g = m.guide.expect("a guided render records its training");
    assert!(g.iterations >= 1);
    assert_eq!(g.training_spp, (1u64 << g.iterations) - 1);
    // half of 10⁸ spp of training would take hours: the time limit ended it
    assert!(g.training_spp < 50_000_000, "{g:?}");
    // the passes after the first (4 spp) double or take what the time left allows
    assert!(m.spp >= 4 && m.spp < 100_000_000, "spp {}", m.spp);
    assert!(m.render_seconds >= 0.5, "{}", m.render_seconds);
    assert!(
        g.training_seconds < m.render_seconds,
        "{g:?} {}",
        m.render_seconds
    );
}

#[test]
fn renders_state_their_error_and_adapt_on_request() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::cornell_path();
    let s = scene.to_str().unwrap();
    let exr = dir.path().join("a.exr");
    let map = dir.path().join("spp.png");
    let out = vrpt(&[
        "render",
        s,
        "--width",
        "24",
        "--height",
        "24",
        "--spp",
        "64",
        "--adaptive",
        "--min-allocation-gain",
        "0",
        "--spp-map",
        map.to_str().unwrap(),
        "-o",
        exr.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("estimated error: relMSE") && err.contains("from 4 replicates"),
        "{err}"
    );
    assert!(
        err.contains("adaptive: ") && err.contains("rounds"),
        "{err}"
    );
    // the bounds on its gain at equal spp: the schedule's at most the ideal (Cauchy–Schwarz:
    // no allocation with the same mean beats n ∝ e), both at least 1 (uniform is one of them)
    let bounds: Vec<f64> = err
        .lines()
        .find(|l| l.contains("ideal (n ∝ e)"))
        .unwrap_or_else(|| panic!("no bound line in {err}"))
        .split(' ')
        .filter_map(|w| w.trim_end_matches(',').parse::<f64>().ok())
        .collect();
    let (ideal, schedule) = (bounds[0], bounds[bounds.len() - 1]);
    assert!(
        1.0 <= schedule && schedule <= ideal + 1e-9,
        "ideal {ideal}, schedule {schedule}"
    );
    assert!(map.is_file());
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    let meta = vrpt::output::RenderMetadata::require(&img, &exr).unwrap();
    assert!(img.metadata.contains_key("estimated_rel_mse"));
    let e = meta.estimate.expect("an estimate");
    assert_eq!((e.replicates, e.method.name()), (4, "replicates"));
    assert!(meta.adaptive_rounds.is_some_and(|n| n >= 3));
    assert!(img.estimated_variance.is_some());
    let counts = img.samples.unwrap();
    assert!(
        counts.iter().min() < counts.iter().max(),
        "adaptive spp should vary"
    );
    // diff prints the image's estimate beside the measured error; adaptive renders do not merge
    let out = vrpt(&["diff", exr.to_str().unwrap(), exr.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("estimated relMSE"));
    // a pair of identical images: the relMSE of one is 0, and only asked for is it printed; the
    // denominator must be a third file
    assert!(!String::from_utf8_lossy(&out.stdout).contains("(pair)"));
    let third = dir.path().join("third.exr");
    std::fs::copy(&exr, &third).unwrap();
    let (e, t) = (exr.to_str().unwrap(), third.to_str().unwrap());
    let out = vrpt(&["diff", e, e, "--pair-denominator", t]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("relMSE of one (pair) 0.000000e0"));
    let out = vrpt(&["diff", e, t, "--pair-denominator", e]);
    assert_one_line_error(&out, "diff --pair-denominator IMAGE", "is IMAGE");
    let m = dir.path().join("m.exr");
    let out = vrpt(&[
        "merge",
        exr.to_str().unwrap(),
        exr.to_str().unwrap(),
        "-o",
        m.to_str().unwrap(),
    ]);
    assert_one_line_error(&out, "merge adaptive", "adaptive");
    // a plain render keeps one set of points (the default: replicates cost MSE), falls back
    // to the per-sample estimate and says it is an upper bound; --target-error acts on the
    // estimate and so takes 4 replicates
    for (args, replicates) in [(vec![], 1), (vec!["--target-error", "1"], 4)] {
        let mut a = vec![
            "render",
            s,
            "--width",
            "8",
            "--height",
            "8",
            "-o",
            exr.to_str().unwrap(),
        ];
        a.extend(args.iter());
        let out = vrpt(&a);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{err}");
        let img = vrpt::image_io::read_exr(&exr).unwrap();
        let e = vrpt::output::RenderMetadata::require(&img, &exr)
            .unwrap()
            .estimate
            .expect("an estimate");
        assert_eq!(e.replicates, replicates, "{args:?}");
        if replicates == 1 {
            assert!(
                err.contains("per sample") && err.contains("upper bound"),
                "{err}"
            );
        }
    }
    for (args, expect) in [
        (
            vec!["--adaptive", "--replicates", "1"],
            "at least 2 replicates",
        ),
        (vec!["--target-error", "0"], "not a positive relMSE"),
        (vec!["--target-error", "x"], "not a positive relMSE"),
        (vec!["--replicates", "0"], "--replicates"),
        (vec!["--spp-map", "a.exr"], "spp map"),
    ] {
        let mut a = vec![
            "render",
            s,
            "--width",
            "8",
            "--height",
            "8",
            "-o",
            exr.to_str().unwrap(),
        ];
        a.extend(args.iter());
        assert_one_line_error(&vrpt(&a), &args.join(" "), expect);
    }
}

/// Second review (issue 34): outputs never overwrite inputs or each other. Each clash is refused
/// with one line naming both flags before any work, and the file it would have destroyed keeps
/// its bytes; paths are compared canonically (`./x`, a symlink).
#[test]
fn outputs_never_overwrite_inputs_or_each_other() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let scene = common::cornell_path();
    let s = scene.to_str().unwrap();
    // a small reference to compare against, and a texture scene to write over
    let reference = d("ref.exr");
    let out = vrpt(&[
        "render", s, "--width", "8", "--height", "8", "--spp", "4", "-o", &reference,
    ]);
    assert!(out.status.success());
    let before = std::fs::read(&reference).unwrap();
    std::os::unix::fs::symlink(&reference, d("link.exr")).unwrap();
    let dot = format!("{}/./ref.exr", dir.path().display());
    let textured = common::shipped_path("textured");
    let texture = textured.join("bricks.png");
    let texture_bytes = std::fs::read(&texture).unwrap();
    let small = ["--width", "8", "--height", "8", "--spp", "4"];
    let (png, link, csv) = (d("a.png"), d("link.exr"), d("t.csv"));
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["render", s, "-o", &reference, "--variance", &dot],
            "--variance",
        ),
        (
            vec!["render", s, "-o", &png, "--spp-map", &png],
            "--spp-map",
        ),
        (
            vec![
                "render",
                textured.to_str().unwrap(),
                "-o",
                texture.to_str().unwrap(),
            ],
            "the scene's file",
        ),
        (
            vec!["compare", s, "--reference", &reference, "--csv", &link],
            "--reference",
        ),
        (
            vec![
                "compare",
                s,
                "--reference",
                &reference,
                "--csv",
                &csv,
                "--json",
                &csv,
            ],
            "--json",
        ),
        (vec!["merge", &reference, &reference, "-o", &link], "input"),
        (
            vec!["diff", &reference, &reference, "--error-map", &reference],
            "--error-map",
        ),
    ];
    for (mut args, expect) in cases {
        if args[0] == "render" {
            args.extend(small);
        }
        let what = args.join(" ");
        assert_one_line_error(&vrpt(&args), &what, expect);
        assert_eq!(
            std::fs::read(&reference).unwrap(),
            before,
            "{what} touched the reference"
        );
    }
    assert_eq!(std::fs::read(&texture).unwrap(), texture_bytes);
}

/// Third review (issue 46): no output of any command that loads a scene writes over a file the
/// scene was read from: its OBJ, scene.toml, MTL and textures. `compare --grid` overwrote a
/// texture and `--csv` replaced scene.toml, since the experiments checked only the scene's
/// path. Each is refused in one line before any work, and every file of the scene keeps its
/// bytes.
#[test]
fn no_command_writes_over_a_file_of_its_scene() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("textured");
    std::fs::create_dir(&scene).unwrap();
    for f in std::fs::read_dir(common::shipped_path("textured")).unwrap() {
        let f = f.unwrap().path();
        std::fs::copy(&f, scene.join(f.file_name().unwrap())).unwrap();
    }
    let files: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(&scene)
        .unwrap()
        .map(|f| f.unwrap().path())
        .map(|f| (f.clone(), std::fs::read(&f).unwrap()))
        .collect();
    let s = scene.to_str().unwrap();
    let reference = dir.path().join("ref.exr");
    let r = reference.to_str().unwrap();
    let small = ["--width", "8", "--height", "8"];
    let mut args = vec!["render", s, "--spp", "2", "-q", "-o", r];
    args.extend(small);
    ok(vrpt(&args));
    let at = |f: &str| scene.join(f).to_str().unwrap().to_string();
    let (png, mtl, toml, obj) = (
        at("bricks.png"),
        at("textured.mtl"),
        at("scene.toml"),
        at("textured.obj"),
    );
    let compare = ["compare", s, "--reference", r, "--runs", "2", "--spp", "1"];
    let converge = [
        "converge",
        s,
        "--reference",
        r,
        "--runs",
        "2",
        "--spp",
        "1,2",
    ];
    let mut cases: Vec<Vec<&str>> = Vec::new();
    for experiment in [&compare[..], &converge[..]] {
        for (flag, file) in [
            ("--csv", &toml),
            ("--csv", &mtl),
            ("--json", &obj),
            ("--report", &toml),
        ] {
            cases.push([experiment, &[flag, file.as_str()]].concat());
        }
    }
    cases.push([&compare[..], &["--grid", png.as_str()]].concat());
    cases.push([&converge[..], &["--plot", png.as_str()]].concat());
    cases.push(vec!["render", s, "--spp-map", &png, "-o", "x.png"]);
    cases.push(vec!["guide", s, "--pixel", "4,4", "-o", &png]);
    for args in cases {
        let what = args.join(" ");
        assert_one_line_error(&vrpt(&args), &what, "the scene's file");
        for (f, bytes) in &files {
            assert!(&std::fs::read(f).unwrap() == bytes, "{what} touched {f:?}");
        }
    }
}

/// Second review (issue 34): every float flag refuses NaN, infinities and values past its
/// documented maximum with one line, never a panic (a time of 1e20 s panicked converting to a
/// Duration; `--exposure nan` was accepted).
#[test]
fn float_flags_refuse_nan_inf_and_huge_values() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::cornell_path();
    let s = scene.to_str().unwrap();
    let out = dir.path().join("x.exr");
    let o = out.to_str().unwrap();
    for (flag, value) in [
        ("--time-limit", "1e20"),
        ("--time-limit", "1e300"),
        ("--time-limit", "inf"),
        ("--time-limit", "nan"),
        ("--exposure", "nan"),
        ("--exposure", "inf"),
        ("--exposure", "-inf"),
        ("--exposure", "1e300"),
        ("--target-error", "nan"),
        ("--target-error", "inf"),
    ] {
        let pair = format!("{flag}={value}");
        let args = ["render", s, "--width", "8", "--height", "8", "-o", o, &pair];
        assert_one_line_error(&vrpt(&args), &pair, flag);
        assert!(!out.exists());
    }
    let r = dir.path().join("r.exr");
    let r = r.to_str().unwrap();
    let made = vrpt(&[
        "render", s, "--width", "8", "--height", "8", "--spp", "4", "-o", r,
    ]);
    assert!(made.status.success());
    for value in ["1e20", "inf", "nan"] {
        let args = [
            "compare",
            s,
            "--reference",
            r,
            "--runs",
            "2",
            "--equal-time",
            value,
        ];
        assert_one_line_error(
            &vrpt(&args),
            &format!("--equal-time {value}"),
            "--equal-time",
        );
    }
    let args = [
        "compare",
        s,
        "--reference",
        r,
        "--runs",
        "2",
        "--exposure",
        "nan",
    ];
    assert_one_line_error(&vrpt(&args), "compare --exposure nan", "--exposure");
}

/// Second review (issue 34): an error estimate from one sample and one replicate is undefined,
/// never zero, and `--target-error` never stops on it (it stopped at 1 spp claiming relMSE 0);
/// more replicates than samples are refused naming both numbers (`--adaptive --spp 5
/// --replicates 256` rendered 256 spp).
#[test]
fn one_sample_claims_no_error_and_replicates_need_their_samples() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::cornell_path();
    let s = scene.to_str().unwrap();
    let exr = dir.path().join("x.exr");
    let o = exr.to_str().unwrap();
    let small = ["render", s, "--width", "8", "--height", "8", "-o", o];
    let mut a = small.to_vec();
    a.extend([
        "--replicates",
        "1",
        "--pass-spp",
        "1",
        "--target-error",
        "1e-9",
        "--spp",
        "4",
    ]);
    let out = vrpt(&a);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    let meta = vrpt::output::RenderMetadata::require(&img, &exr).unwrap();
    assert_eq!(
        meta.spp, 4,
        "a target of 1e-9 is not reached: the render runs to --spp"
    );
    let mut a = small.to_vec();
    a.extend(["--replicates", "1", "--spp", "1"]);
    let out = vrpt(&a);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && err.contains("estimated error: undefined"),
        "{err}"
    );
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    let e = vrpt::output::RenderMetadata::require(&img, &exr)
        .unwrap()
        .estimate
        .unwrap();
    assert_eq!(e.method.name(), "undefined");
    assert!(e.rel_mse.is_nan() && img.estimated_variance.is_none());
    for extra in [
        vec!["--adaptive", "--spp", "5", "--replicates", "256"],
        vec!["--spp", "3", "--replicates", "4"],
    ] {
        let mut a = small.to_vec();
        a.extend(extra.iter());
        assert_one_line_error(&vrpt(&a), &extra.join(" "), "needs at least");
    }
}

/// Second review (issue 34, suspected by reading): an adaptive render whose samples start near
/// the last sample index, 2³² − 1. Hot pixels take more samples than the spp, so a pixel's next
/// index reached 2³², every later round still gave it one sample, and the next count's
/// `2³² − next` underflowed (a panic with overflow checks, as this test's binary has; a wrapped
/// sample index without). Equal rounds (a time limit) make many rounds after the hottest pixel
/// runs out. Now the rounds end where a pixel has no index left, and the render writes what it
/// took.
#[test]
fn adaptive_rounds_stop_at_the_last_sample_index() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("x.exr");
    let scene = common::cornell_path();
    let first = (u32::MAX - 4095).to_string();
    let out = vrpt(&[
        "render",
        scene.to_str().unwrap(),
        "--width",
        "24",
        "--height",
        "24",
        "--spp",
        "4096",
        "--first-sample",
        &first,
        "--adaptive",
        "--replicates",
        "2",
        "--pass-spp",
        "64",
        "--time-limit",
        "100",
        "-o",
        exr.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    assert!(img.pixels.iter().all(|p| p.is_finite()));
    let counts = img.samples.unwrap();
    assert!(
        counts.iter().all(|&n| n >= 2),
        "every pixel in every replicate"
    );
    assert!(
        counts.iter().all(|&n| n as u64 <= 2 * 4096),
        "no index past the last"
    );
}

/// `--min-allocation-gain`: a render whose first round says allocating cannot pay (here the
/// bar is set out of reach) says so and finishes as uniform passes of one set: every pixel the
/// requested spp, the per-sample estimate of one set (and the metadata records one replicate
/// and `per-sample`, not the first round's four), one adaptive round in the metadata. The flag needs
/// `--adaptive` and a finite gain ≥ 0, each refused in one line.
#[test]
fn adaptive_renders_finish_uniformly_where_allocating_cannot_pay() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("u.exr");
    let scene = common::cornell_path();
    let s = scene.to_str().unwrap();
    let args = [
        "render",
        s,
        "--width",
        "24",
        "--height",
        "24",
        "--spp",
        "64",
        "--adaptive",
    ];
    let out = vrpt(
        &[
            &args[..],
            &["--min-allocation-gain", "1e9", "-o", exr.to_str().unwrap()],
        ]
        .concat(),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("the rest rendered as uniform passes"), "{err}");
    assert!(err.contains("per sample"), "{err}");
    let img = vrpt::image_io::read_exr(&exr).unwrap();
    let meta = vrpt::output::RenderMetadata::require(&img, &exr).unwrap();
    assert_eq!((meta.spp, meta.adaptive_rounds), (64, Some(1)));
    let e = meta.estimate.expect("the estimate's keys");
    assert_eq!(
        (e.replicates, e.method),
        (1, vrpt::output::EstimateMethod::PerSample)
    );
    assert!(img.samples.unwrap().iter().all(|&n| n == 64));
    assert_one_line_error(
        &vrpt(&[&args[..], &["--min-allocation-gain", "-1"]].concat()),
        "negative gain",
        "not a gain",
    );
    assert_one_line_error(
        &vrpt(&[&args[..], &["--min-allocation-gain", "inf"]].concat()),
        "infinite gain",
        "not a gain",
    );
    assert_one_line_error(
        &vrpt(&["render", s, "--min-allocation-gain", "1"]),
        "gain without --adaptive",
        "--adaptive",
    );
}

proptest::proptest! {
    /// Second review (issue 34): the float flags' parsers take any string without a panic and
    /// accept only values inside their documented ranges (times up to `MAX_SECONDS`, exposures
    /// within ±`MAX_EXPOSURE`), whatever the float: NaN, ±inf, 1e300, subnormals, any bits.
    #[test]
    fn float_flag_parsers_accept_only_their_ranges(bits in proptest::prelude::any::<u64>(), pick in 0..4usize) {
        let x = f64::from_bits(bits);
        let text = [x.to_string(), format!("{x:e}"), format!("{}", x as f32), format!("-{x}")][pick].clone();
        if let Ok(t) = vrpt::limits::parse_seconds(&text) {
            proptest::prop_assert!(t > 0.0 && t <= vrpt::limits::MAX_SECONDS);
            proptest::prop_assert!(vrpt::limits::duration("--time-limit", t).is_ok());
        }
        if let Ok(e) = vrpt::limits::parse_exposure(&text) {
            proptest::prop_assert!(e.abs() <= vrpt::limits::MAX_EXPOSURE);
        }
        // the library's own check of a time takes any float without a panic
        let _ = vrpt::limits::duration("--time-limit", x);
    }
}

/// Issue 37: `vrpt points` draws each sampler's set (PNG or SVG) and writes the numbers the
/// issue names (`sampler`, `n`, `dims`, `l2_star_discrepancy`, `radial_spectrum`); the
/// independent set's discrepancy is near `√(5/(36N))`, the others' far below; a dimension the
/// layout lacks is refused with one line.
#[test]
fn points_draws_the_sets_and_writes_their_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let (png, svg, json) = (
        dir.path().join("p.png"),
        dir.path().join("p.svg"),
        dir.path().join("p.json"),
    );
    let out = vrpt(&[
        "points",
        "--n",
        "64",
        "--realisations",
        "64",
        "-o",
        png.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(png.is_file());
    let rows: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for r in rows {
        for key in [
            "sampler",
            "n",
            "dims",
            "l2_star_discrepancy",
            "radial_spectrum",
        ] {
            assert!(r.get(key).is_some(), "{key} missing");
        }
    }
    let d = |k: usize| rows[k]["l2_star_discrepancy"].as_f64().unwrap();
    let expected = (5.0f64 / (36.0 * 64.0)).sqrt();
    assert!((d(0) / expected - 1.0).abs() < 0.3, "independent {}", d(0));
    assert!(d(1) < 0.5 * d(0) && d(2) < 0.5 * d(0));
    let out = vrpt(&[
        "points",
        "--dims",
        "direction-2",
        "--sampler",
        "sobol",
        "-o",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
    assert_one_line_error(
        &vrpt(&["points", "--dims", "colour-1"]),
        "bad dims",
        "not a 2D dimension",
    );
    // after a warp, with the dependent pair: one more row, which fails the box test (no point
    // of (x, x + ½) lies in [0,½)×[0,0.3)), and a discrepancy curve per row
    let out = vrpt(&[
        "points",
        "--n",
        "64",
        "--realisations",
        "4",
        "--warp",
        "phong:20",
        "--dependent",
        "-o",
        png.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 4);
    assert_eq!(rows[3]["sampler"], "dependent pair of independent");
    assert_eq!(rows[3]["box_fraction"].as_f64(), Some(0.0));
    for r in rows {
        assert_eq!(r["discrepancy_curve"].as_array().unwrap().len(), 8, "{r}");
        assert!(r["discrepancy_slope"].as_f64().is_some());
    }
    assert_one_line_error(
        &vrpt(&["points", "--warp", "sphere"]),
        "bad warp",
        "not a warp",
    );
}

/// Issue 37: `vrpt integrate` writes a row per integrand × sampler × directions × N with the
/// fields the issue names, and covariance rows with their pair; independent rows predict σ²/N;
/// `-o` draws the variance-against-N plots, and variance rows carry their fitted slope except
/// where `p ∝ f` (the variance there is rounding).
#[test]
fn integrate_writes_its_rows() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("i.json");
    let png = dir.path().join("i.png");
    let out = vrpt(&[
        "integrate",
        "--integrand",
        "smooth,lobe",
        "--n",
        "16,64",
        "--repetitions",
        "500",
        "--json",
        json.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    // smooth: 1 domain, lobe: 3; × 4 samplers × 2 N, plus a covariance row per (…, sampler)
    assert_eq!(rows.len(), 4 * 4 * 2 + 4 * 4);
    for r in rows {
        for key in [
            "integrand",
            "sampler",
            "directions",
            "n",
            "repetitions",
            "exact",
        ] {
            assert!(r.get(key).is_some(), "{key} missing in {r}");
        }
        let measured = ["mean", "mean_ci", "variance", "variance_ci"];
        let cov = ["pair", "covariance", "covariance_ci"];
        assert!(
            measured.iter().all(|k| r.get(*k).is_some()) || cov.iter().all(|k| r.get(*k).is_some()),
            "{r}"
        );
    }
    assert!(rows
        .iter()
        .filter(|r| r["sampler"] == "independent" && r.get("variance").is_some())
        .all(|r| r["prediction"] == "sigma2/N" && r.get("predicted_variance").is_some()));
    assert!(png.is_file());
    // the plots as SVG too; a picture of another kind is refused in one line, before any work
    let svg = dir.path().join("i.svg");
    let quick = [
        "integrate",
        "--integrand",
        "smooth",
        "--n",
        "16",
        "--repetitions",
        "100",
        "-o",
    ];
    let out = vrpt(&[&quick[..], &[svg.to_str().unwrap()]].concat());
    assert!(out.status.success());
    assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
    let exr = dir.path().join("i.exr");
    assert_one_line_error(
        &vrpt(&[&quick[..], &[exr.to_str().unwrap()]].concat()),
        "an EXR plot",
        "written as .png or .svg",
    );
    assert!(!exr.exists());
    for r in rows.iter().filter(|r| r.get("variance").is_some()) {
        let proportional = r["directions"] == "phong";
        assert_eq!(r.get("slope").is_none(), proportional, "{r}");
    }
}
