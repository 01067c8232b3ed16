//! Scene loading: OBJ + MTL + scene.toml into triangles, materials and emitters, and a clear
//! error for each kind of bad input.

use crate::common;

use common::write;
use glam::Vec3;
use vrpt::error::Error;
use vrpt::scene;

const MTL: &str = "\
newmtl white
Kd 0.7 0.7 0.7
newmtl shiny
Kd 0.6 0.5 0.4
Ks 0.6 0.2 0.1
Ns 50
newmtl lamp
Kd 0 0 0
Ke 10 8 6
";

const OBJ: &str = "\
mtllib test.mtl
v 0 0 0
v 1 0 0
v 1 0 1
v 0 0 1
v 0 1 0
v 1 1 0
v 0.5 2 0.5
vn 0 1 0
usemtl white
f 1//1 4//1 3//1 2//1
usemtl shiny
f 1 2 6 5
usemtl lamp
f 5 6 7
usemtl nosuchmaterial
f 1 2 7
";

#[test]
fn obj_with_mtl_loads_triangles_materials_and_emitters() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "test.mtl", MTL);
    let obj = write(dir.path(), "test.obj", OBJ);
    let s = scene::load(&obj).unwrap();
    // two quads (2 triangles each) + 2 triangles
    assert_eq!(s.triangle_count(), 6);
    // white, shiny, lamp + the grey fallback for the unknown name
    assert_eq!(s.materials.len(), 4);
    let shiny = s.materials.iter().find(|m| m.name == "shiny").unwrap();
    // Kd + Ks = 1.2 in red: both scaled by 1/1.2 in that channel only
    assert!((shiny.kd() - Vec3::new(0.5, 0.5, 0.4)).length() < 1e-6);
    assert!((shiny.ks() - Vec3::new(0.5, 0.2, 0.1)).length() < 1e-6);
    assert_eq!(shiny.exponent(), 50.0);
    let lamp = s.materials.iter().find(|m| m.name == "lamp").unwrap();
    assert_eq!(lamp.emission, Vec3::new(10.0, 8.0, 6.0));
    assert_eq!(s.lights.len(), 1);
    // the lamp triangle (0,1,0) (1,1,0) (0.5,2,0.5): area = |e1 × e2| / 2
    let e1 = Vec3::new(1.0, 0.0, 0.0);
    let e2 = Vec3::new(0.5, 1.0, 0.5);
    assert!((s.lights.emitters[0].area - 0.5 * e1.cross(e2).length()).abs() < 1e-6);
    assert!(s.warnings.iter().any(|w| w.contains("nosuchmaterial")));
    assert!(s
        .warnings
        .iter()
        .any(|w| w.contains("shiny") && w.contains("scaled")));
    // a scene with emitters has a black environment by default
    assert_eq!(s.environment(), &Vec3::ZERO.into());
    // each triangle's material: the floor quad is 'white' and has the file's normal
    let white = s.materials.iter().position(|m| m.name == "white").unwrap() as u32;
    let floor: Vec<_> = s.shading.iter().filter(|t| t.material == white).collect();
    assert_eq!(floor.len(), 2);
    assert!(floor.iter().all(|t| t.normals[0] == Vec3::Y));
}

/// A triangle whose vertex normals are its geometric normal, bit for bit (none in the file, or
/// the file's equal to it) is flat: a hit's shading normal is the geometric one, bit for bit;
/// a triangle with other vertex normals interpolates them and normalises the sum — also one
/// whose normal differs from `ng` only in the sign of a zero, which turns the shading frame.
#[test]
fn flat_triangles_shade_with_their_own_normal() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "test.mtl", MTL);
    // a flat quad without normals on the tilted plane z = 0.37x + 0.11y (its normal interpolated
    // and normalised again would come back an ulp or so off), beside it a smooth triangle at
    // z = 0 whose vertex normals lean, a triangle at z = 0 given its own normal (0, 0, 1), and
    // one given (−0, 0, 1)
    let obj = write(
        dir.path(),
        "flat.obj",
        "mtllib test.mtl\nusemtl white\n\
         v 0 0 0\nv 1 0 0.37\nv 1 1 0.48\nv 0 1 0.11\nv 2 0 0\nv 3 0 0\nv 2 1 0\n\
         v 4 0 0\nv 5 0 0\nv 4 1 0\nv 6 0 0\nv 7 0 0\nv 6 1 0\n\
         vn 0.6 0 1\nvn -0.4 0.8 1\nvn 0 -1 1\nvn 0 0 1\nvn -0 0 1\n\
         f 1 2 3 4\nf 5//1 6//2 7//3\nf 8//4 9//4 10//4\nf 11//5 12//5 13//5\n",
    );
    let s = scene::load(&obj).unwrap();
    let mut stack = vrpt::accel::TraceStack::default();
    // a point in each of the quad's halves, the smooth triangle, the one with its normal and the
    // one with a −0
    for (x, y, flat) in [
        (0.6f32, 0.3, true),
        (0.2, 0.6, true),
        (2.2, 0.3, false),
        (4.2, 0.3, true),
        (6.2, 0.3, false),
    ] {
        for (z, dir) in [(1.0f32, -Vec3::Z), (-1.0, Vec3::Z)] {
            let o = Vec3::new(x, y, z);
            let hit = s.intersect(&mut stack, o, dir, f32::INFINITY).unwrap();
            assert_eq!(s.shading[hit.prim as usize].flat, flat, "x = {x}");
            let p = s.surface(&hit);
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            if flat {
                assert_eq!(
                    bits(p.ns),
                    bits(p.ng),
                    "x = {x}: a flat triangle's shading normal"
                );
                continue;
            }
            let sh = &s.shading[hit.prim as usize];
            let b0 = 1.0 - hit.b1 - hit.b2;
            let n =
                (sh.normals[0] * b0 + sh.normals[1] * hit.b1 + sh.normals[2] * hit.b2).normalize();
            assert_eq!(bits(p.ns), bits(n), "x = {x}: the interpolated normal");
            if x < 6.0 {
                assert!(p.ns.dot(p.ng) < 0.99, "its vertex normals lean: {}", p.ns);
            } else {
                assert!(p.ns.x.is_sign_negative() && !p.ng.x.is_sign_negative());
            }
        }
    }
}

#[test]
fn missing_mtl_falls_back_to_grey_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "test.obj", OBJ);
    let s = scene::load(&obj).unwrap();
    assert!(s
        .warnings
        .iter()
        .any(|w| w.contains("test.mtl") && w.contains("not found")));
    assert_eq!(s.materials.len(), 1);
    assert!(s.lights.is_empty());
    // no emitters: the studio (a grey sky of 0.5 and a key light from behind the camera, above
    // and to its right), so the scene is visible and shaded
    let env = s.environment();
    assert!(env.map().is_some(), "{:?}", s.warnings);
    assert!(s.warnings.iter().any(|w| w.contains("key light")));
    let eye = s.camera.eye;
    let back = (eye - s.camera.target).normalize();
    assert!((env.radiance(-back) - Vec3::splat(0.5)).abs().max_element() < 1e-6);
    let key = (back + s.camera.up + 0.5 * s.camera.up.cross(back)).normalize();
    assert!(env.radiance(key).x > 10.0, "{:?}", env.radiance(key));
}

/// The studio's key light gives a white surface facing it the irradiance it promises: a
/// surface of normal `n` under the map gathers `∫ L cosθ dω = π·0.5 (the sky) + 0.6π·cosθ_key`
/// (the disc, 8° across, counted as its exact texels), summed here over the map's texels at
/// their centres (the midpoint rule on 128 × 64 texels: about 0.5 % error on the disc's edge).
#[test]
fn the_studio_light_gives_the_irradiance_it_promises() {
    use vrpt::environment::Environment;
    let key = Vec3::new(0.3, 0.8, 0.52).normalize();
    let env = Environment::studio(key);
    let map = env.map().unwrap();
    let (w, h) = map.size();
    for n in [key, Vec3::Y, Vec3::Z, Vec3::X, -key] {
        let mut e = 0.0f64;
        for y in 0..h {
            let (t0, t1) = (
                std::f64::consts::PI * y as f64 / h as f64,
                std::f64::consts::PI * (y + 1) as f64 / h as f64,
            );
            let sr = 2.0 * std::f64::consts::PI / w as f64 * (t0.cos() - t1.cos());
            for x in 0..w {
                let uv = glam::Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                let d = map.direction(uv);
                let c = d.dot(n).max(0.0) as f64;
                e += env.radiance(d).x as f64 * c * sr;
            }
        }
        let want = std::f64::consts::PI * (0.5 + 0.6 * key.dot(n).max(0.0) as f64);
        assert!((e - want).abs() < 0.02 * want, "n {n}: {e} against {want}");
    }
}

#[test]
fn scene_toml_sets_camera_environment_and_defaults() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "test.mtl", MTL);
    write(dir.path(), "test.obj", OBJ);
    write(
        dir.path(),
        "scene.toml",
        "obj = \"test.obj\"\n[camera]\neye = [0, 1, 5]\ntarget = [0, 1, 0]\nfov = 30\n\
         [environment]\nradiance = [0.5, 0.5, 0.5]\n[render]\nwidth = 40\nspp = 3\n",
    );
    for path in [
        dir.path().to_path_buf(),
        dir.path().join("scene.toml"),
        dir.path().join("test.obj"),
    ] {
        let s = scene::load(&path).unwrap();
        assert_eq!(s.camera.eye, Vec3::new(0.0, 1.0, 5.0));
        assert_eq!(s.camera.fov_deg, 30.0);
        assert_eq!(s.environment(), &Vec3::splat(0.5).into());
        assert_eq!(s.defaults.width, Some(40));
        assert_eq!(s.defaults.spp, Some(3));
        assert_eq!(s.defaults.height, None);
    }
}

fn load_err(files: &[(&str, &str)], target: &str) -> Error {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        write(dir.path(), name, text);
    }
    match scene::load(&dir.path().join(target)) {
        Ok(_) => panic!("loading {target} should fail"),
        Err(e) => e,
    }
}

#[test]
fn bad_input_gives_its_error() {
    let e = load_err(&[], "nothing.obj");
    assert!(matches!(e, Error::NotFound { .. }), "{e}");

    let e = load_err(
        &[("a.obj", "v 0 0 0\nv 1 0 abc\nv 0 1 0\nf 1 2 3\n")],
        "a.obj",
    );
    assert!(matches!(e, Error::Obj { .. }), "{e}");
    assert!(e.to_string().contains("line 2"), "{e}");

    let e = load_err(
        &[("a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")],
        "a.obj",
    );
    assert!(
        matches!(e, Error::Obj { .. }) && e.to_string().contains("line 4"),
        "{e}"
    );

    let e = load_err(
        &[
            (
                "a.obj",
                "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
            ),
            ("a.mtl", "newmtl m\nKd 0.5 zero 0.5\n"),
        ],
        "a.obj",
    );
    assert!(matches!(e, Error::Mtl { .. }), "{e}");
    assert!(e.to_string().contains("a.mtl"), "{e}");

    let e = load_err(
        &[("scene.toml", "obj = \"a.obj\"\n[camera\n")],
        "scene.toml",
    );
    assert!(
        matches!(e, Error::Toml { .. }) && e.to_string().contains("line 2"),
        "{e}"
    );

    let e = load_err(
        &[("scene.toml", "obj = \"a.obj\"\nspp = 3\n")],
        "scene.toml",
    );
    assert!(matches!(e, Error::Toml { .. }), "{e}");

    let e = load_err(&[("a.obj", "# nothing here\n")], "a.obj");
    assert!(
        matches!(e, Error::Scene { .. }) && e.to_string().contains("no"),
        "{e}"
    );

    let e = load_err(&[("notes.txt", "hello")], "notes.txt");
    assert!(matches!(e, Error::Scene { .. }), "{e}");

    // a folder with no scene.toml
    let e = load_err(&[("a.obj", "v 0 0 0\n")], "");
    assert!(e.to_string().contains("scene.toml"), "{e}");
}

#[test]
fn shipped_scenes_load() {
    for name in [
        "cornell-box",
        "glossy-plates",
        "checker-plane",
        "night-hall",
    ] {
        let s = common::shipped(name);
        assert!(!s.lights.is_empty(), "{name} has emitters");
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
    }
    // the lamp's one light sits inside a closed glass shade (12 quads: two nested boxes)
    let lamp = common::shipped("lamp");
    assert!(lamp.warnings.is_empty(), "lamp: {:?}", lamp.warnings);
    assert_eq!(lamp.lights.emitters.len(), 1);
    let glass = (lamp.shading.iter())
        .filter(|t| lamp.materials[t.material as usize].specular.is_some())
        .count();
    assert_eq!(glass, 24);
    let cb = common::shipped("cornell-box");
    assert_eq!(cb.triangle_count(), 32);
    assert_eq!(cb.defaults.spp, Some(64));
    // the light faces down: its triangles' normals point to -y
    // the night hall's 160 lights are rectangles, each of two triangles
    let hall = common::shipped("night-hall");
    assert_eq!(hall.lights.emitters.len(), 160);
    assert!(hall
        .lights
        .emitters
        .iter()
        .all(|e| matches!(e.shape, vrpt::lights::Shape::Rectangle { .. })));
    // and the box's lamp's two triangles are sampled as one rectangle
    assert_eq!(cb.lights.emitters.len(), 1);
    let lamp = &cb.lights.emitters[0];
    assert!(matches!(lamp.shape, vrpt::lights::Shape::Rectangle { .. }));
    assert!(lamp.n.y < -0.99);
    for prim in lamp.prims {
        assert!(cb.shading[prim as usize].ng.y < -0.99);
    }
}

/// The guiding scenes are what the scene list says: in `gap` the lamp faces away from room A
/// (every point with z ≥ 0 lies behind its plane), so with direct light only (max depth 2) the
/// pixels of room A are black — only those that look through the gap into the lit room see
/// anything — while with bounces every pixel of room A receives light; `door-dark` is the door
/// with room A darker (a lower mean at the same spp and seed).
#[test]
fn the_guiding_scenes_are_lit_as_documented() {
    use vrpt::render::RenderSettings;
    let gap = common::shipped("gap");
    assert_eq!(gap.lights.emitters.len(), 1);
    let lamp = &gap.lights.emitters[0];
    assert!(lamp.n.z < -0.99, "the lamp faces -z, into room B");
    for prim in lamp.prims {
        for v in gap.accel.vertices(prim) {
            assert!(v.z < -0.01, "the lamp lies in room B: {v}");
        }
    }
    let lit = |scene: &vrpt::scene::Scene, max_depth: u32, spp: u32| {
        let settings = RenderSettings {
            width: 48,
            height: 32,
            spp,
            max_depth,
            ..Default::default()
        };
        let (film, _) = common::render_quiet(scene, &settings);
        let img = film.mean_image();
        let nonzero = img.iter().filter(|c| c.max_element() > 0.0).count();
        let mean = img.iter().map(|c| c.x as f64).sum::<f64>() / img.len() as f64;
        (nonzero as f64 / img.len() as f64, mean)
    };
    // a zero is exact (no light sample or path found anything), so the lit pixels at depth 2
    // are those that see the lit room through the gap: about 2 of 48 columns
    let (direct, _) = lit(&gap, 2, 16);
    assert!(direct < 0.1, "{:.1}% lit directly", direct * 100.0);
    // with bounces, about 1 path in 200 of room A finds light (7.7% of the pixels lit at 16
    // spp): at 1024 spp a pixel stays black with probability (1 − 1/200)^1024 ≈ 0.6%, so
    // nearly all are lit (measured 96.7%: 51 of 1536 black, mostly in the box's shadow; the
    // bound allows 153, 14 sd of a Poisson count of mean 51 away)
    let (bounced, _) = lit(&gap, 10, 1024);
    assert!(bounced > 0.9, "{:.1}% lit with bounces", bounced * 100.0);
    let (_, door) = lit(&common::shipped("door"), 10, 64);
    let (_, dark) = lit(&common::shipped("door-dark"), 10, 64);
    assert!(dark < 0.8 * door, "door-dark {dark} against door {door}");
}
