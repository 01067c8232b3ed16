//! Scenes made elsewhere (issue 47), each property of the public OBJ scenes that once failed as
//! a small file of its own: end-of-line comments and statements vrpt does not use, texture
//! names written on other systems, a texture that is not there, glass and mirrors from `illum`,
//! an interior seen from outside, an outdoor world lit by one small dim lamp, an object inside
//! an enclosing backdrop, and a render that comes out black; `vrpt info`. Plus the physics of
//! the delta lobes: a white furnace through glass and mirrors, and the Fresnel choice.

use crate::common;
use common::{vrpt, write};

use glam::Vec3;
use std::path::{Path, PathBuf};
use vrpt::bsdf::{fresnel_dielectric, Specular};
use vrpt::render::RenderSettings;
use vrpt::scene::{self, Scene};

/// The mean luminance of a render of `scene` (`w`×`h`, `spp`, `max_depth`).
fn mean_luminance(scene: &Scene, w: u32, spp: u32, max_depth: u32) -> (f64, Vec<Vec3>) {
    let s = RenderSettings {
        width: w,
        height: w,
        spp,
        max_depth,
        seed: common::seed(47),
        ..RenderSettings::for_scene(scene)
    };
    let (film, _) = common::render_quiet(scene, &s);
    let img = film.mean_image();
    let lum = img
        .iter()
        .map(|p| vrpt::math::luminance(*p) as f64)
        .sum::<f64>();
    (lum / img.len() as f64, img)
}

/// A folder `name` under `dir` holding `files` (name, text).
fn folder(dir: &Path, name: &str, files: &[(&str, &str)]) -> PathBuf {
    let f = dir.join(name);
    std::fs::create_dir_all(&f).unwrap();
    for (n, t) in files {
        write(&f, n, t);
    }
    f
}

/// A quad (corners counter-clockwise about its normal) as OBJ lines, its vertices from `base`.
fn quad(corners: [[f32; 3]; 4], base: usize, material: &str) -> String {
    let mut s = String::new();
    for c in corners {
        s += &format!("v {} {} {}\n", c[0], c[1], c[2]);
    }
    s += &format!(
        "usemtl {material}\nf {} {} {} {}\n",
        base + 1,
        base + 2,
        base + 3,
        base + 4
    );
    s
}

/// The McGuire Cornell box files' habits: `Ka … # Red` (a comment at the end of a line), `Tr`
/// beside `d`, unknown keywords, a `#` inside a material name (3ds Max's `_Material #25`), a
/// malformed number in a statement vrpt does not use (skipped with a note; refused by
/// `--strict`), and a malformed number in one it uses (always refused, with its line).
#[test]
fn mtl_comments_and_statements_vrpt_does_not_use() {
    let dir = tempfile::tempdir().unwrap();
    let mtl = "newmtl red # the left wall\n  Ka 0.63 0.065 0.05 # Red\n  Kd 0.63 0.065 0.05\n\
               \td 1.0\n\tTr 0.0000\n  Pwr 3\n  illum 2\nnewmtl _Material #25\nKd 0.2 0.4 0.6\n\
               Ka 0.0000 0.0000 0.0000c\nnewmtl light\nKe 5 5 5 # bright\n";
    let obj = format!(
        "mtllib s.mtl # the library\n{}{}{}",
        quad(
            [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
            0,
            "red"
        ),
        quad(
            [[1., 0., 0.], [2., 0., 0.], [2., 1., 0.], [1., 1., 0.]],
            4,
            "_Material #25"
        ),
        quad(
            [[0., 2., 1.], [0., 2., 0.], [2., 2., 0.], [2., 2., 1.]],
            8,
            "light"
        )
    );
    let f = folder(dir.path(), "a", &[("s.obj", &obj), ("s.mtl", mtl)]);
    let s = scene::load(&f.join("s.obj")).unwrap();
    let names: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["red", "_Material #25", "light"]);
    assert_eq!(s.materials[1].kd(), Vec3::new(0.2, 0.4, 0.6));
    assert_eq!(s.materials[2].emission, Vec3::splat(5.0));
    let all = s.warnings.join("\n");
    assert!(
        all.contains("Ka ×2") && all.contains("Pwr ×1") && all.contains("Tr ×1"),
        "{all}"
    );
    assert!(all.contains("line 10") && all.contains("0.0000c"), "{all}");
    let strict = scene::load_with(&f.join("s.obj"), true)
        .err()
        .unwrap()
        .to_string();
    assert!(
        strict.contains("0.0000c") && strict.contains("--strict"),
        "{strict}"
    );
    // a malformed number where vrpt reads it: refused, lenient or not
    let bad = mtl.replace("Kd 0.2 0.4 0.6", "Kd 0.2 0.4 0.6c");
    let f = folder(dir.path(), "b", &[("s.obj", &obj), ("s.mtl", &bad)]);
    let e = scene::load(&f.join("s.obj")).err().unwrap().to_string();
    assert!(
        e.contains("line 9") && e.contains("0.6c") && e.contains("Kd"),
        "{e}"
    );
}

/// Texture names as other systems wrote them: another letter case (`SP_LUK.JPG` for
/// `sp_luk.JPG`), `\` separators, quotes, a path of the author's machine whose file lies beside
/// the MTL; each found with a warning naming the file, refused by `--strict`. A texture that is
/// nowhere leaves its material's constant colour, with a warning.
#[test]
fn texture_names_written_elsewhere_are_found() {
    let dir = tempfile::tempdir().unwrap();
    let f = folder(dir.path(), "t", &[]);
    std::fs::create_dir(f.join("Maps")).unwrap();
    let img = image::RgbImage::from_fn(2, 2, |x, _| image::Rgb([200 * x as u8, 50, 50]));
    img.save(f.join("Maps/sp_luk.JPG")).unwrap();
    img.save(f.join("wood.png")).unwrap();
    let cases = [
        ("map_Kd maps\\SP_LUK.JPG", Some("letter case")),
        ("map_Kd \"wood.png\"", None),
        (
            "map_Kd C:\\Users\\bob\\textures\\WOOD.PNG",
            Some("file name alone"),
        ),
    ];
    for (statement, how) in cases {
        let mtl = format!("newmtl m\nKd 1 1 1\n{statement}\n");
        let obj = format!(
            "mtllib s.mtl\nvt 0 0\nvt 1 0\nvt 1 1\n{}",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl m\nf 1/1 2/2 3/3\n"
        );
        write(&f, "s.mtl", &mtl);
        write(&f, "s.obj", &obj);
        let s = scene::load(&f.join("s.obj")).unwrap();
        assert_eq!(s.textures.textures.len(), 1, "{statement}");
        assert!(s.materials[0].maps.kd.is_some());
        let all = s.warnings.join("\n");
        match how {
            Some(h) => {
                assert!(all.contains(h), "{statement}: {all}");
                let e = scene::load_with(&f.join("s.obj"), true).err().unwrap();
                assert!(e.to_string().contains("--strict"), "{e}");
            }
            None => assert!(scene::load_with(&f.join("s.obj"), true).is_ok(), "{all}"),
        }
    }
    write(&f, "s.mtl", "newmtl m\nKd 0.3 0.6 0.9\nmap_Kd gone.png\n");
    let s = scene::load(&f.join("s.obj")).unwrap();
    assert!(s.materials[0].maps.kd.is_none());
    assert_eq!(s.materials[0].kd(), Vec3::new(0.3, 0.6, 0.9));
    let all = s.warnings.join("\n");
    assert!(
        all.contains("gone.png") && all.contains("constant colour"),
        "{all}"
    );
    assert!(scene::load_with(&f.join("s.obj"), true).is_err());
}

/// A white furnace: under a uniform white sky, a closed glass object (a faceted icosphere, index
/// 1.5, clear) and a perfect mirror sphere scatter every path back to the sky with throughput 1
/// (reflection weighs 1; a refraction in weighs 1/η² and the one out η²), so every pixel is 1:
/// a path that loses or gains energy shows at once. Only paths cut by the depth limit (64
/// segments, each internal bounce a reflection of at most a few percent outside total internal
/// reflection) come back 0; the bound 0.999 on the mean allows a thousandth of them, and the
/// largest pixel may pass 1 by f32 rounding of the η² factors only.
#[test]
fn a_white_furnace_through_glass_and_mirrors_stays_white() {
    let dir = tempfile::tempdir().unwrap();
    for (name, mtl) in [
        ("glass", "newmtl m\nNi 1.5\nTf 0 0 0\nillum 7\n"),
        ("water", "newmtl m\nNi 1.33\nd 0.5\nillum 4\n"),
        ("mirror", "newmtl m\nKd 0 0 0\nKs 1 1 1\nillum 3\n"),
        ("fresnel-mirror", "newmtl m\nKd 0 0 0\nKs 1 1 1\nillum 5\n"),
    ] {
        let obj = format!("mtllib s.mtl\n{}", common::icosphere_obj(1.0, 2, "m"));
        // the sky uniform and white (a scene without emitters is otherwise lit by the studio)
        let toml = "obj = \"s.obj\"\n[environment]\nradiance = [1, 1, 1]\n";
        let files = [
            ("s.obj", obj.as_str()),
            ("s.mtl", mtl),
            ("scene.toml", toml),
        ];
        let f = folder(dir.path(), name, &files);
        let s = scene::load(&f).unwrap();
        assert!(s.materials[0].specular.is_some(), "{name}");
        let (mean, img) = mean_luminance(&s, 24, 32, 64);
        let max = img.iter().map(|p| p.max_element()).fold(0.0f32, f32::max);
        let min = img.iter().map(|p| p.min_element()).fold(f32::MAX, f32::min);
        assert!(
            mean > 0.999 && max < 1.0 + 1e-4,
            "{name}: mean {mean}, max {max}"
        );
        assert!(min > 0.9, "{name}: a pixel at {min}");
    }
}

/// The dielectric chooses reflection with the Fresnel reflectance's probability, from each side
/// and past the critical angle: at each of 12 angles per side, 40,000 choices by uniform
/// numbers; the count of reflections is binomial, z = (k − NF)/√(NF(1−F)), held within 4.5 (24
/// tests: a false alarm below 2·10⁻⁴). A choice off by 5% of F is found at most angles.
#[test]
fn the_dielectric_chooses_by_fresnel() {
    let glass = Specular::Dielectric {
        ior: 1.5,
        transmittance: Vec3::ONE,
    };
    let n = 40_000u32;
    let mut next = common::uniform_pairs(common::seed(4747));
    for entering in [true, false] {
        for k in 0..12 {
            let cos = 0.04 + 0.08 * k as f32;
            let wo = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
            let eta = if entering { 1.5 } else { 1.0 / 1.5 };
            let f = fresnel_dielectric(cos, eta).0 as f64;
            let mut reflected = 0u32;
            for _ in 0..n / 2 {
                let u = next();
                for x in [u.x, u.y] {
                    let s = glass.sample(wo, entering, x).unwrap();
                    reflected += (!s.transmitted) as u32;
                    if s.transmitted {
                        // energy: what crosses carries (1 − F) of the flux, η²·weight = 1
                        assert!((s.weight.x * (eta * eta) - 1.0).abs() < 1e-5);
                    }
                }
            }
            let (nf, k) = (n as f64 * f, reflected as f64);
            if f >= 1.0 {
                assert_eq!(reflected, n, "total internal reflection at cos {cos}");
                continue;
            }
            let z = (k - nf) / (nf * (1.0 - f)).sqrt();
            assert!(z.abs() < 4.5, "entering {entering}, cos {cos}: z {z}");
        }
    }
}

/// An axis-aligned box `lo..hi` as OBJ quads of `material` from vertex `base`, faces turned
/// inward (a room) or outward (a block).
fn box_obj(lo: [f32; 3], hi: [f32; 3], base: usize, material: &str, inward: bool) -> String {
    let [x0, y0, z0] = lo;
    let [x1, y1, z1] = hi;
    // each face counter-clockwise seen from outside
    let faces = [
        [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]], // bottom (-y)
        [[x0, y1, z0], [x0, y1, z1], [x1, y1, z1], [x1, y1, z0]], // top (+y)
        [[x0, y0, z0], [x0, y1, z0], [x1, y1, z0], [x1, y0, z0]], // -z
        [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], // +z
        [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]], // -x
        [[x1, y0, z0], [x1, y1, z0], [x1, y1, z1], [x1, y0, z1]], // +x
    ];
    let mut s = String::new();
    for (k, mut f) in faces.into_iter().enumerate() {
        if inward {
            f.reverse();
        }
        s += &quad(f, base + 4 * k, material);
    }
    s
}

/// Scenes without a scene.toml give a picture: an interior whose walls face in (from outside
/// the camera sees only their backs, and the lamp is inside) puts the camera inside; an outdoor
/// world lit by one small dim lamp, and a model inside an enclosing backdrop, each come out
/// lit. A mean luminance of 0.01 is ten times the black threshold and far below what each
/// gives when it works (0.1 to 0.5).
#[test]
fn scenes_without_a_description_give_a_picture() {
    let dir = tempfile::tempdir().unwrap();
    let mtl = "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n";
    // a square lamp at height y, facing down
    let lamp = |y: f32, half: f32, base: usize| {
        quad(
            [
                [-half, y, -half],
                [half, y, -half],
                [half, y, half],
                [-half, y, half],
            ],
            base,
            "lamp",
        )
    };
    let room = format!(
        "mtllib s.mtl\n{}{}{}",
        box_obj([-2., 0., -3.], [2., 3., 3.], 0, "wall", true),
        box_obj([-0.5, 0., -0.5], [0.5, 1., 0.5], 24, "wall", false),
        lamp(2.99, 0.3, 48)
    );
    let dim = "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\n";
    let outdoor = format!(
        "mtllib s.mtl\n{}{}{}",
        quad(
            [
                [-500., 0., -500.],
                [-500., 0., 500.],
                [500., 0., 500.],
                [500., 0., -500.]
            ],
            0,
            "wall"
        ),
        box_obj([-5., 0., -5.], [5., 8., 5.], 4, "wall", false),
        lamp(20.0, 0.005, 28)
    );
    let mut backdrop = format!("mtllib s.mtl\n{}", common::icosphere_obj(10.0, 2, "wall"));
    // the backdrop faces in: each face's winding reversed
    backdrop = backdrop
        .lines()
        .map(|l| match l.strip_prefix("f ") {
            Some(r) => {
                let v: Vec<&str> = r.split_whitespace().collect();
                format!("f {} {} {}\n", v[0], v[2], v[1])
            }
            None => format!("{l}\n"),
        })
        .collect();
    let n = backdrop.lines().filter(|l| l.starts_with("v ")).count();
    backdrop += &box_obj([-1., -1., -1.], [1., 1., 1.], n, "wall", false);
    backdrop += &lamp(8.0, 1.0, n + 24);
    for (name, obj, mtl, says) in [
        ("room", room.as_str(), mtl, "placed inside"),
        ("outdoor", outdoor.as_str(), dim, "light almost nothing"),
        ("backdrop", backdrop.as_str(), mtl, "placed inside"),
    ] {
        let f = folder(dir.path(), name, &[("s.obj", obj), ("s.mtl", mtl)]);
        let s = scene::load(&f.join("s.obj")).unwrap();
        let all = s.warnings.join("\n");
        assert!(all.contains(says), "{name}: {all}");
        let (mean, _) = mean_luminance(&s, 16, 16, 6);
        assert!(mean > 0.01, "{name}: mean luminance {mean}");
    }
}

/// A render that comes out black ends with one line saying why and what would light it: here
/// the scene.toml's environment is black and the only lamp faces the sky.
#[test]
fn a_black_render_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let mtl = "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n";
    let obj = format!(
        "mtllib s.mtl\n{}{}",
        quad(
            [[-5., 0., -5.], [-5., 0., 5.], [5., 0., 5.], [5., 0., -5.]],
            0,
            "wall"
        ),
        quad(
            [[-1., 3., -1.], [-1., 3., 1.], [1., 3., 1.], [1., 3., -1.]],
            4,
            "lamp"
        )
    );
    let toml = "obj = \"s.obj\"\n[camera]\neye = [0.0, 2.0, 8.0]\ntarget = [0.0, 0.0, 0.0]\n\
                fov = 40.0\n[environment]\nradiance = [0.0, 0.0, 0.0]\n";
    let f = folder(
        dir.path(),
        "black",
        &[("s.obj", &obj), ("s.mtl", mtl), ("scene.toml", toml)],
    );
    let png = dir.path().join("b.png");
    let out = vrpt(&[
        "render",
        f.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "4",
        "-q",
        "-o",
        png.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.contains("the image is black"))
        .unwrap_or_else(|| panic!("{stderr}"));
    assert!(
        line.contains("1 emitters") && line.contains("radiance = [1, 1, 1]"),
        "{line}"
    );
}

/// `vrpt info` says what the loader found: the shipped glass scene's triangles, its glass and
/// mirror, its emitter, the camera from its scene.toml, memory, warnings.
#[test]
fn info_says_what_the_loader_found() {
    let scene = common::shipped_path("glass");
    let out = common::vrpt_ok(&["info", scene.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    for want in [
        "triangles: 1294",
        "'glass': glass, index 1.5",
        "'mirror': mirror",
        "emitters: 1",
        "camera: eye (0.0000, 1.0000, 3.9000)",
        "bytes per triangle",
        "scene.toml",
        "glass.mtl",
    ] {
        assert!(text.contains(want), "{want}: {text}");
    }
    let out = vrpt(&["info", "no/such/scene.obj"]);
    common::assert_one_line_error(&out, "info of a missing scene", "not found");
}

/// A scene too large for the memory is refused with the estimate before the text is read or the
/// mesh built (`VRPT_MEMORY_LIMIT` stands for a small machine): the Cornell box's 1.4 kB of
/// text passes at 8 kB, its 32 triangles at 400 B each do not; at 1 kB even the text does not.
#[test]
fn a_scene_too_large_for_the_memory_is_refused_before_it_is_built() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    for (limit, expect) in [("8000", "a scene of 32 triangles"), ("1000", "reading its")] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_vrpt"))
            .args(["render", common::cornell_path().to_str().unwrap(), "-o"])
            .arg(&out)
            .env("VRPT_MEMORY_LIMIT", limit)
            .output()
            .unwrap();
        common::assert_one_line_error(&o, limit, expect);
        assert!(!out.exists());
    }
}
