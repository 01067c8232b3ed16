//! A fuzzing test on stable Rust: proptest feeds the OBJ, MTL, `scene.toml`, EXR and texture
//! readers mutated copies of the shipped scenes, of a vrpt EXR and of a PNG texture (bytes
//! flipped, cut, duplicated and spliced; tokens replaced by hostile ones: NaN, infinities, huge
//! and negative numbers, stray indices and keywords; PNG headers that lie about their size). A
//! scene that loads is also rendered (2×2, 1 spp).
//!
//! Contract for every input: `Ok`, or an `Err` whose message is one line of bounded length;
//! never a panic (proptest reports it, with the shrunk input), and never an allocation
//! proportional to a number in the input: a counting allocator records the largest single
//! allocation, which must stay under [`MAX_ALLOCATION`] (the inputs are a few KB; a reader that
//! trusted a declared size or count would ask for far more). A hang would stop the test run.
//!
//! `VRPT_FUZZ_CASES=N` runs N cases (default 2000, a few seconds); `VRPT_FUZZ_SEED=S` draws
//! other ones (default: proptest's fixed deterministic seed, so CI runs the same cases).

mod common;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The largest single allocation allowed while reading an input.
const MAX_ALLOCATION: usize = 64 << 20;

/// The system allocator, recording the largest single request (this test binary holds one
/// test, so no other test's allocations are counted).
struct Counting;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Tokens a hostile or broken file is made of.
const TOKENS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e39",
    "-1e39",
    "1e30",
    "0",
    "-0",
    "-1",
    "4294967296",
    "99999999999999999999",
    "1e-45",
    "0.5",
    "/",
    "//",
    "1//",
    "-9/-9/-9",
    "\n",
    "\r\n",
    " ",
    "",
    "#",
    "[",
    "]",
    "[[",
    "=",
    "\"",
    "'",
    "{",
    "}",
    ",",
    "v",
    "vt",
    "vn",
    "f",
    "l",
    "p",
    "o",
    "g",
    "s",
    "usemtl",
    "mtllib",
    "newmtl",
    "Kd",
    "Ks",
    "Ke",
    "Ns",
    "Ni",
    "d",
    "Tr",
    "map_Kd",
    "obj",
    "camera",
    "eye",
    "target",
    "up",
    "fov",
    "environment",
    "radiance",
    "render",
    "width",
    "height",
    "spp",
    "max_depth",
    "passes",
    "pass_spp",
    "replicates",
    "16,32",
    "16,,0",
    "[camera]",
    "[render]",
    "é",
    "\u{0}",
    "\u{feff}",
];

/// One edit of a byte string.
#[derive(Clone, Debug)]
enum Edit {
    /// Flip some bits of the byte at a position.
    Flip(f64, u8),
    /// Remove a range.
    Cut(f64, usize),
    /// Copy a range to another position.
    Duplicate(f64, usize, f64),
    /// Insert a range of another seed file.
    Splice(f64, usize, usize, f64),
    /// Replace the whitespace-separated token at a position with a hostile one.
    Token(f64, usize),
    /// Truncate at a position.
    Truncate(f64),
}

fn edit() -> impl Strategy<Value = Edit> {
    let at = 0.0..1.0f64;
    prop_oneof![
        (at.clone(), 1..=255u8).prop_map(|(a, b)| Edit::Flip(a, b)),
        (at.clone(), 1..64usize).prop_map(|(a, n)| Edit::Cut(a, n)),
        (at.clone(), 1..256usize, at.clone()).prop_map(|(a, n, b)| Edit::Duplicate(a, n, b)),
        (at.clone(), 1..256usize, 0..64usize, at.clone())
            .prop_map(|(a, n, k, b)| Edit::Splice(a, n, k, b)),
        (at.clone(), 0..TOKENS.len()).prop_map(|(a, t)| Edit::Token(a, t)),
        (at.clone(), 0..TOKENS.len()).prop_map(|(a, t)| Edit::Token(a, t)),
        (at.clone(), 0..TOKENS.len()).prop_map(|(a, t)| Edit::Token(a, t)),
        at.prop_map(Edit::Truncate),
    ]
}

fn pos(len: usize, at: f64) -> usize {
    ((len as f64 * at) as usize).min(len)
}

fn apply(mut b: Vec<u8>, edits: &[Edit], seeds: &[Vec<u8>]) -> Vec<u8> {
    for e in edits {
        let len = b.len();
        match *e {
            Edit::Flip(a, x) if len > 0 => {
                let i = pos(len - 1, a);
                b[i] ^= x;
            }
            Edit::Cut(a, n) => {
                let i = pos(len, a);
                b.drain(i..(i + n).min(len));
            }
            Edit::Duplicate(a, n, to) => {
                let i = pos(len, a);
                let part = b[i..(i + n).min(len)].to_vec();
                let j = pos(len, to);
                b.splice(j..j, part);
            }
            Edit::Splice(a, n, k, to) => {
                let src = &seeds[k % seeds.len()];
                let i = pos(src.len(), a);
                let part = src[i..(i + n).min(src.len())].to_vec();
                let j = pos(len, to);
                b.splice(j..j, part);
            }
            Edit::Token(a, t) => {
                let i = pos(len, a);
                let is_space = |c: &u8| c.is_ascii_whitespace();
                let start = b[..i].iter().rposition(is_space).map_or(0, |k| k + 1);
                let end = b[i..].iter().position(is_space).map_or(len, |k| i + k);
                b.splice(start..end.max(start), TOKENS[t].bytes());
            }
            Edit::Truncate(a) => b.truncate(pos(len, a)),
            _ => {}
        }
    }
    b
}

/// Which reader an input goes to.
#[derive(Clone, Copy, Debug)]
enum Target {
    Obj,
    Mtl,
    Toml,
    Exr,
    /// A texture the MTL's first material reads (`map_Kd tex.png`), its header's size rewritten
    /// to a lie in some cases (the IHDR checksum fixed, so only the size lies).
    Png,
}

/// `png` with its IHDR's width and height set to `w`, `h` and its checksum fixed.
fn lie_about_size(mut png: Vec<u8>, w: u32, h: u32) -> Vec<u8> {
    if png.len() >= 33 && &png[12..16] == b"IHDR" {
        png[16..20].copy_from_slice(&w.to_be_bytes());
        png[20..24].copy_from_slice(&h.to_be_bytes());
        let mut crc = flate2::Crc::new();
        crc.update(&png[12..29]);
        png[29..33].copy_from_slice(&crc.sum().to_be_bytes());
    }
    png
}

/// The contract on an error: one line, bounded.
fn check_error(e: &vrpt::error::Error) -> Result<(), TestCaseError> {
    let m = e.to_string();
    prop_assert!(!m.contains('\n'), "error of several lines: {m:?}");
    prop_assert!(
        m.len() <= 600,
        "error of {} bytes: {:?}…",
        m.len(),
        &m[..200]
    );
    Ok(())
}

#[test]
fn readers_survive_mutated_inputs() {
    let cases: u32 = std::env::var("VRPT_FUZZ_CASES")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(2000);
    let rng = match std::env::var("VRPT_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
    {
        Some(s) => {
            let mut seed = [0u8; 32];
            seed[..8].copy_from_slice(&s.to_le_bytes());
            TestRng::from_seed(RngAlgorithm::ChaCha, &seed)
        }
        None => TestRng::deterministic_rng(RngAlgorithm::ChaCha),
    };
    let config = Config {
        cases,
        failure_persistence: None,
        max_shrink_iters: 2000,
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(config, rng);

    // seed corpus: every shipped scene's files, and a small vrpt EXR
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut scenes = Vec::new();
    for name in [
        "cornell-box",
        "glossy-plates",
        "lit-checker",
        "checker-plane",
    ] {
        let folder = common::shipped_path(name);
        let toml = std::fs::read(folder.join("scene.toml")).unwrap();
        let desc = vrpt::scene::description::Description::load(&folder.join("scene.toml")).unwrap();
        let obj_path = folder.join(&desc.obj);
        let obj = std::fs::read(&obj_path).unwrap();
        let mtl = std::fs::read_dir(&folder)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| p.extension().is_some_and(|e| e == "mtl"))
            .map(|p| std::fs::read(p).unwrap())
            .unwrap_or_default();
        scenes.push((obj, mtl, toml));
    }
    let exr_path = d.join("seed.exr");
    {
        let scene = common::shipped("cornell-box");
        let s = vrpt::render::RenderSettings {
            width: 6,
            height: 5,
            spp: 2,
            ..Default::default()
        };
        // its metadata with the keys that hold lists and counts (the passes a render recorded,
        // issue 46), so mutations reach their readers
        let (film, stats) = common::render_quiet(&scene, &s);
        let meta = vrpt::output::RenderMetadata {
            pass_spp: Some(1),
            passes: vec![1, 1],
            shard: Some((0, 1)),
            ..vrpt::output::RenderMetadata::new(&scene, &s, &stats)
        };
        let img = vrpt::output::render_image(&film, &meta);
        vrpt::image_io::write_exr(&exr_path, &img).unwrap();
    }
    let exr = std::fs::read(&exr_path).unwrap();
    let png_path = d.join("seed.png");
    image::RgbaImage::from_fn(4, 4, |x, y| {
        image::Rgba([40 * x as u8, 60 * y as u8, 90, 255])
    })
    .save(&png_path)
    .unwrap();
    let png = std::fs::read(&png_path).unwrap();
    let mut seeds: Vec<Vec<u8>> = scenes
        .iter()
        .flat_map(|(o, m, t)| [o.clone(), m.clone(), t.clone()])
        .collect();
    seeds.push(exr.clone());

    let strategy = (
        0..5usize,
        0..scenes.len(),
        prop::collection::vec(edit(), 1..6),
        prop::option::of((1..=u32::MAX, 1..=u32::MAX)),
    );
    let (ok, err) = (std::cell::Cell::new(0u32), std::cell::Cell::new(0u32));
    let result = runner.run(&strategy, |(target, k, edits, lie)| {
        let target = [
            Target::Obj,
            Target::Mtl,
            Target::Toml,
            Target::Exr,
            Target::Png,
        ][target];
        let (obj, mtl, toml) = &scenes[k];
        let case = d.join("case");
        let _ = std::fs::remove_dir_all(&case);
        std::fs::create_dir(&case).unwrap();
        // every scene is written as scene.toml naming scene.obj, which names its MTL as shipped
        let toml = String::from_utf8_lossy(toml);
        let obj_name = toml
            .lines()
            .find_map(|l| l.trim().strip_prefix("obj"))
            .unwrap()
            .to_string();
        let mut files = [obj.clone(), mtl.clone(), toml.as_bytes().to_vec()];
        let mtl_name = String::from_utf8_lossy(obj)
            .lines()
            .find_map(|l| l.strip_prefix("mtllib ").map(|n| n.trim().to_string()))
            .unwrap_or_else(|| "none.mtl".into());
        LARGEST.store(0, Ordering::Relaxed);
        let outcome = match target {
            Target::Exr => {
                let p = case.join("x.exr");
                std::fs::write(&p, apply(exr.clone(), &edits, &seeds)).unwrap();
                LARGEST.store(0, Ordering::Relaxed);
                vrpt::image_io::read_exr(&p)
                    .and_then(|img| vrpt::output::RenderMetadata::from_image(&img, &p).map(|_| ()))
            }
            t => {
                if matches!(t, Target::Png) {
                    // the seed scene, its first material textured by the mutated PNG
                    let mut bytes = apply(png.clone(), &edits, &seeds);
                    if let Some((w, h)) = lie {
                        bytes = lie_about_size(png.clone(), w % 100_000 + 1, h % 100_000 + 1);
                    }
                    std::fs::write(case.join("tex.png"), bytes).unwrap();
                    let mtl = String::from_utf8_lossy(&files[1]).replacen(
                        "\nKd ",
                        "\nmap_Kd tex.png\nKd ",
                        1,
                    );
                    files[1] = mtl.into_bytes();
                } else {
                    let i = t as usize;
                    files[i] = apply(std::mem::take(&mut files[i]), &edits, &seeds);
                }
                let obj_file = obj_name
                    .trim()
                    .trim_start_matches('=')
                    .trim()
                    .trim_matches('"');
                std::fs::write(case.join(obj_file), &files[0]).unwrap();
                std::fs::write(case.join(&mtl_name), &files[1]).unwrap();
                std::fs::write(case.join("scene.toml"), &files[2]).unwrap();
                LARGEST.store(0, Ordering::Relaxed);
                load_and_render(&case)
            }
        };
        let largest = LARGEST.load(Ordering::Relaxed);
        prop_assert!(
            largest <= MAX_ALLOCATION,
            "{target:?}: an allocation of {largest} bytes"
        );
        match &outcome {
            Ok(()) => ok.set(ok.get() + 1),
            Err(e) => {
                err.set(err.get() + 1);
                check_error(e)?;
            }
        }
        Ok(())
    });
    let (ok, err) = (ok.get(), err.get());
    eprintln!("fuzz: {cases} cases, {ok} read, {err} refused with one line");
    if let Err(e) = result {
        panic!("{e}");
    }
    // the mutations must reach both outcomes, or the test checks nothing
    assert!(
        ok > cases / 20 && err > cases / 20,
        "{ok} ok, {err} refused"
    );
}

/// Load the scene in `folder` and, if it loads, render 2×2 pixels at 1 spp.
fn load_and_render(folder: &Path) -> vrpt::error::Result<()> {
    let scene = vrpt::scene::load(folder)?;
    let settings = vrpt::render::RenderSettings {
        width: 2,
        height: 2,
        spp: 1,
        threads: Some(1),
        ..vrpt::render::RenderSettings::for_scene(&scene)
    };
    let (film, _) = vrpt::render::render(&scene, &settings, &vrpt::render::NoProgress)?;
    assert!(film.mean_image().iter().all(|p| p.is_finite()));
    Ok(())
}
