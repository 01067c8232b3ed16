//! The HTML reports (`--report` of compare, converge and diff) opened in a real browser.
//!
//! Each test makes a report the way a user would (the `vrpt` binary on the shipped Cornell box),
//! writes what the page must show into an EXPECT.json taken from the run's own outputs (the
//! `--json` results, the EXR files, the library's metrics), and runs
//! `tests/browser/check_report.mjs` (Node, no packages) which drives headless Chromium through
//! chromedriver: no JavaScript errors or outside loads, the metrics shown equal the JSON results,
//! exposure +1 doubles the drawn linear value, every drawn pixel equals the tone-mapped data, the
//! A/B divide and its drag, the false-colour views with their colour bar, zoom, and the pixel
//! inspector showing the values and standard errors stored in the EXR files. Screenshots go to
//! `target/tmp/report-screens/<kind>/` (artifacts to look at).
//!
//! The browser comes from Debian's `chromium` and `chromium-driver` (`.ci/run` installs them).
//! Without them these tests say so on stderr and pass, unless `VRPT_REQUIRE_BROWSER=1` (set by
//! `.ci/run`), when a missing browser fails them.

use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;
use vrpt::analysis::metrics::metrics;
use vrpt::analysis::report::decode_halves;
use vrpt::image_io::{read_exr, RgbImage};

use crate::common;
use common::vrpt_ok;

/// Chromium, chromedriver and node, or None (with the reason) when one is missing.
fn browser() -> Option<()> {
    let path = |var: &str, default: &str| {
        std::env::var_os(var).map_or_else(|| PathBuf::from(default), PathBuf::from)
    };
    let mut missing = Vec::new();
    for (var, default) in [
        ("CHROMIUM", "/usr/bin/chromium"),
        ("CHROMEDRIVER", "/usr/bin/chromedriver"),
    ] {
        let p = path(var, default);
        if !p.is_file() {
            missing.push(format!("{} (${var})", p.display()));
        }
    }
    if Command::new("node").arg("--version").output().is_err() {
        missing.push("node".into());
    }
    if missing.is_empty() {
        return Some(());
    }
    let why = format!(
        "browser report test: {} missing (apt install chromium chromium-driver nodejs)",
        missing.join(", ")
    );
    if std::env::var_os("VRPT_REQUIRE_BROWSER").is_some_and(|v| v != "0") {
        panic!("{why}; VRPT_REQUIRE_BROWSER is set");
    }
    eprintln!("SKIPPED {why}");
    None
}

/// The report's JSON payload.
fn payload(report: &Path) -> Value {
    let html = std::fs::read_to_string(report).unwrap();
    let start = r#"<script type="application/json" id="vrpt-data">"#;
    let at = html.find(start).expect("data tag") + start.len();
    let end = html[at..].find("</script>").unwrap();
    serde_json::from_str(&html[at..at + end].replace("<\\/", "</")).unwrap()
}

/// The payload's image of this name (and group) must be the EXR's pixels, as half floats: the
/// report shows what the renders wrote. Its standard errors are √ of the EXR's variance.
fn assert_payload_holds(p: &Value, name: &str, group: &str, exr: &RgbImage) {
    let im = p["images"]
        .as_array()
        .unwrap()
        .iter()
        .find(|i| i["name"] == name && i["group"] == group)
        .unwrap_or_else(|| panic!("no image {name} ({group}) in the report"));
    // each value is the EXR's rounded to the nearest binary16
    let as_halves = |v: &mut dyn Iterator<Item = glam::Vec3>| -> Vec<f32> {
        v.flat_map(|p| p.to_array())
            .map(|c| half::f16::from_f32(c).to_f32())
            .collect()
    };
    let rgb = decode_halves(im["rgb"].as_str().unwrap()).unwrap();
    assert!(
        rgb == as_halves(&mut exr.pixels.iter().copied()),
        "the report's {name} ({group}) is not the EXR's image"
    );
    let var = exr.variance.as_ref().unwrap();
    let se = decode_halves(im["stderr"].as_str().unwrap()).unwrap();
    assert!(
        se == as_halves(&mut var.iter().map(|v| v.max(glam::Vec3::ZERO).powf(0.5))),
        "the report's {name} ({group}) standard errors are not the EXR's"
    );
}

/// Probe pixels for the exposure and A/B checks: every channel of `shown` in [0.06, 0.4] (not
/// black at exposure 0, below 0.8 at +1: unsaturated), and some channel differing from `other` by
/// more than 0.03 (several 8-bit steps there, so A and B are told apart); up to 8, spread over
/// the candidates.
fn probes(shown: &RgbImage, other: &RgbImage) -> Vec<[u32; 2]> {
    let w = shown.width;
    let found: Vec<[u32; 2]> = (0..shown.pixels.len())
        .filter(|&i| {
            let (v, r) = (shown.pixels[i], other.pixels[i]);
            v.min_element() >= 0.06 && v.max_element() <= 0.4 && (v - r).abs().max_element() > 0.03
        })
        .map(|i| [i as u32 % w, i as u32 / w])
        .collect();
    assert!(found.len() >= 3, "too few probe pixels: {}", found.len());
    let step = found.len().div_ceil(8);
    found.into_iter().step_by(step).collect()
}

fn rgb(v: glam::Vec3) -> Value {
    json!([v.x, v.y, v.z])
}

/// The hover check: pixel (x, y) of each named EXR, its value and standard error.
fn hover(x: u32, y: u32, images: &[(&str, &RgbImage)]) -> Value {
    let i = (y * images[0].1.width + x) as usize;
    let mut values = serde_json::Map::new();
    let mut stderr = serde_json::Map::new();
    for (name, img) in images {
        values.insert(name.to_string(), rgb(img.pixels[i]));
        let v = img.variance.as_ref().unwrap()[i];
        stderr.insert(name.to_string(), rgb(v.max(glam::Vec3::ZERO).powf(0.5)));
    }
    json!({"x": x, "y": y, "values": values, "stderr": stderr})
}

/// Run the page checker; its output is printed (cargo shows it for a failing test).
fn check_in_browser(report: &Path, expect: &Value, kind: &str) {
    let dir = report.parent().unwrap();
    let expect_path = dir.join(format!("{kind}-expect.json"));
    std::fs::write(&expect_path, serde_json::to_string_pretty(expect).unwrap()).unwrap();
    let shots = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("report-screens")
        .join(kind);
    let _ = std::fs::remove_dir_all(&shots);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/browser/check_report.mjs");
    let o = Command::new("node")
        .arg(script)
        .arg(report)
        .arg(&expect_path)
        .arg(&shots)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    println!("{text}{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        o.status.success(),
        "the {kind} report failed in the browser"
    );
    // the checker ran its checks (a run that checked nothing is no pass)
    let passed: u32 = text
        .lines()
        .find_map(|l| l.strip_suffix(" passed, 0 failed"))
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!(passed >= 50, "only {passed} checks ran");
}

/// Render the shipped Cornell box at 48×48 to `out` (an EXR) and read it back: one replicate,
/// as compare and converge render each run (they measure the error across runs).
fn render(spp: u32, seed: u64, strategy: &str, out: &Path) -> RgbImage {
    let scene = common::cornell_path();
    let (spp, seed) = (spp.to_string(), seed.to_string());
    vrpt_ok(&[
        "render",
        scene.to_str().unwrap(),
        "--width",
        "48",
        "--height",
        "48",
        "--spp",
        &spp,
        "--seed",
        &seed,
        "--strategy",
        strategy,
        "--replicates",
        "1",
        // as `vrpt compare` and `converge` run a strategy: without edge rays (their experiments
        // weigh the samplers and strategies alone; `analysis::experiments`)
        "--edge-rays",
        "0",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    read_exr(out).unwrap()
}

/// A 48×48 reference of the shipped Cornell box (MIS, 512 spp): its path, the scene's path
/// and the image.
fn reference(dir: &Path) -> (PathBuf, String, RgbImage) {
    let r = dir.join("ref.exr");
    let image = render(512, 99, "mis", &r);
    (
        r,
        common::cornell_path().to_str().unwrap().to_string(),
        image,
    )
}

/// What the page must show, and the browser run: the metrics, probe pixels and the A/B pair
/// of `shown` (the image the page shows first) against the reference, and a hover over the
/// `pick`-th probe pixel reading `shown` and the reference.
fn check_expected(
    report: &Path,
    kind: &str,
    (metrics, summary): (Vec<Value>, Option<Value>),
    (name, shown): (&str, &RgbImage),
    r: &RgbImage,
    pick: fn(usize) -> usize,
) {
    let probe = probes(shown, r);
    let [hx, hy] = probe[pick(probe.len())];
    let expect = json!({
        "metrics": metrics,
        "probe": probe,
        "hover": hover(hx, hy, &[(name, shown), ("reference", r)]),
        "ab": {"a": name, "b": "reference"},
        "summary": summary,
    });
    check_in_browser(report, &expect, kind);
}

#[test]
fn compare_report_in_a_browser() {
    if browser().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (r, scene, ref_image) = reference(dir.path());
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let (report, results) = (dir.path().join("compare.html"), dir.path().join("c.json"));
    vrpt_ok(&[
        "compare",
        &scene,
        "--reference",
        &s(&r),
        "--strategies",
        "combined,mis",
        "--spp",
        "16",
        "--runs",
        "2",
        "--seed",
        "1",
        "-q",
        "--json",
        &s(&results),
        "--report",
        &s(&report),
    ]);
    // the first run of each strategy is the render with seed 1: the same image as an EXR
    let mis = render(16, 1, "mis", &dir.path().join("mis.exr"));
    let r = ref_image;
    let p = payload(&report);
    assert_payload_holds(&p, "mis", "", &mis);
    assert_payload_holds(&p, "reference", "", &r);

    // every number of the run's JSON results, in table 0, row = strategy
    let c: Value = serde_json::from_str(&std::fs::read_to_string(&results).unwrap()).unwrap();
    let mut expect_metrics = Vec::new();
    for row in c["rows"].as_array().unwrap() {
        for (k, v) in row.as_object().unwrap() {
            if v.is_number() && k != "runs" {
                expect_metrics
                    .push(json!({"table": 0, "row": row["strategy"], "column": k, "value": v}));
            }
        }
    }
    assert!(expect_metrics.len() >= 20);
    // the summary: the strategies by MSE, from the run's JSON; mis is best but listed second,
    // so opening on it is the summary's doing
    let mut by_mse: Vec<(String, f64)> = c["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["strategy"].as_str().unwrap().to_string(),
                r["mse"].as_f64().unwrap(),
            )
        })
        .collect();
    by_mse.sort_by(|a, b| a.1.total_cmp(&b.1));
    assert_eq!(by_mse[0].0, "mis");
    let summary = json!({
        "key": "mse",
        "order": by_mse.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>(),
        "values": by_mse.iter().map(|(n, v)| (n.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
    });
    check_expected(
        &report,
        "compare",
        (expect_metrics, Some(summary)),
        ("mis", &mis),
        &r,
        |n| n / 2,
    );
}

#[test]
fn converge_report_in_a_browser() {
    if browser().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (r, scene, ref_image) = reference(dir.path());
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let (report, results) = (dir.path().join("converge.html"), dir.path().join("c.json"));
    vrpt_ok(&[
        "converge",
        &scene,
        "--reference",
        &s(&r),
        "--strategies",
        "nee,mis",
        "--spp",
        "8,32",
        "--runs",
        "2",
        "--seed",
        "1",
        "-q",
        "--json",
        &s(&results),
        "--report",
        &s(&report),
    ]);
    // the first image shown is nee at 8 spp (the first group); mis at 32 spp is another group
    let nee8 = render(8, 1, "nee", &dir.path().join("nee8.exr"));
    let mis32 = render(32, 1, "mis", &dir.path().join("mis32.exr"));
    let r = ref_image;
    let p = payload(&report);
    assert_payload_holds(&p, "nee", "8 spp", &nee8);
    assert_payload_holds(&p, "mis", "32 spp", &mis32);
    assert!(p["plot_svg"].as_str().unwrap().starts_with("<svg"));

    // table 0: the fitted slopes; table 1: MSE by spp (mean over runs)
    let c: Value = serde_json::from_str(&std::fs::read_to_string(&results).unwrap()).unwrap();
    let mut expect_metrics = Vec::new();
    for sl in c["slopes"].as_array().unwrap() {
        for k in ["mse_slope", "rel_mse_slope"] {
            expect_metrics
                .push(json!({"table": 0, "row": sl["strategy"], "column": k, "value": sl[k]}));
        }
    }
    for pt in c["points"].as_array().unwrap() {
        let col = format!("mse_{}", pt["spp"]);
        expect_metrics
            .push(json!({"table": 1, "row": pt["strategy"], "column": col, "value": pt["mse"]}));
    }
    check_expected(
        &report,
        "converge",
        (expect_metrics, None),
        ("nee", &nee8),
        &r,
        |_| 0,
    );
}

#[test]
fn diff_report_in_a_browser() {
    if browser().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (r, _, ref_image) = reference(dir.path());
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let img = dir.path().join("nee.exr");
    let a = render(16, 5, "nee", &img);
    let report = dir.path().join("diff.html");
    vrpt_ok(&["diff", &s(&img), &s(&r), "--report", &s(&report)]);
    let r = ref_image;
    let p = payload(&report);
    assert_payload_holds(&p, "nee.exr", "", &a);
    assert_payload_holds(&p, "reference", "", &r);
    // the metrics, computed here by the library from the two EXR files
    let m = metrics(&a.pixels, &r.pixels);
    let expect_metrics: Vec<Value> = [
        ("mse", m.mse),
        ("rel_mse", m.rel_mse),
        ("rmse", m.rmse),
        ("mae", m.mae),
        ("mean_signed_error", m.mean_signed_error),
    ]
    .iter()
    .map(|(k, v)| json!({"table": 0, "row": "whole image", "column": k, "value": v}))
    .collect();
    check_expected(
        &report,
        "diff",
        (expect_metrics, None),
        ("nee.exr", &a),
        &r,
        |n| n - 1,
    );
}

/// The same compare run twice gives the same report, but for the measured times and what is
/// derived from them (time per run and efficiency): the images, the error metrics and the
/// settings are byte for byte the same. (With equal times the files would be equal: the page
/// holds no date or random id; `report.rs` tests that at the unit level.)
#[test]
fn a_report_is_deterministic_but_for_its_timings() {
    let dir = tempfile::tempdir().unwrap();
    let (r, scene, _) = reference(dir.path());
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let run = |name: &str| {
        let out = dir.path().join(name);
        vrpt_ok(&[
            "compare",
            &scene,
            "--reference",
            &s(&r),
            "--strategies",
            "importance,nee",
            "--spp",
            "4",
            "--runs",
            "2",
            "-q",
            "--report",
            &s(&out),
        ]);
        let mut p = payload(&out);
        for row in p["tables"][0]["rows"].as_array_mut().unwrap() {
            let row = row.as_object_mut().unwrap();
            assert!(row.remove("seconds").is_some() && row.remove("efficiency").is_some());
        }
        // the page around the payload
        let html = std::fs::read_to_string(&out).unwrap();
        let (head, rest) = html.split_once(r#"id="vrpt-data">"#).unwrap();
        let tail = &rest[rest.find("</script>").unwrap()..];
        (p, format!("{head}{tail}"))
    };
    let ((a, page_a), (b, page_b)) = (run("a.html"), run("b.html"));
    assert_eq!(a, b);
    assert_eq!(page_a, page_b);
}
