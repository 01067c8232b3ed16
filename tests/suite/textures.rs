//! Textures from the MTL (issue 23): a texture shared by materials loads once, options are read,
//! a cutout (`map_d`) casts exactly the shadow of its opaque half, bump and normal maps tilt the
//! shading normal as their formulas say, and the shipped textured scene renders. (sRGB decoding
//! and bilinear lookups are unit tests of `src/texture.rs`; a missing texture is a case of
//! tests/suite/hostile_inputs.rs.)

use crate::common;

use common::write;
use glam::{Vec2, Vec3};
use std::path::Path;
use vrpt::render::RenderSettings;
use vrpt::stats::{normal_critical_value, sidak};
use vrpt::strategy::Strategy;

/// Straight down −z, as `-Vec3::Z` is: with −0.0 in x and y (see
/// `axis_rays_with_signed_zeros_hit_what_brute_force_hits`).
const DOWN_Z: Vec3 = Vec3::new(-0.0, -0.0, -1.0);

/// An 8-bit PNG of `w × h` RGBA pixels from `f(x, y)` (row 0 at the top).
fn png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) {
    let img = image::RgbaImage::from_fn(w, h, |x, y| image::Rgba(f(x, y)));
    img.save(path).unwrap();
}

/// Two materials naming the same file with the same decoding share one texture; `map_d` of
/// the same file is loaded again (linear, not sRGB); `-s`/`-o` are read; an unknown option is
/// skipped with a warning.
#[test]
fn a_shared_texture_loads_once_and_options_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    png(&d.join("t.png"), 4, 4, |_, _| [255, 128, 0, 255]);
    write(
        d,
        "s.mtl",
        "newmtl a\nKd 1 1 1\nmap_Kd -s 2 3 1 -o 0.5 0.25 t.png\nnewmtl b\nKd 1 1 1\n\
         map_Kd -clamp on t.png\nmap_d t.png\n",
    );
    write(
        d,
        "s.obj",
        "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nusemtl a\n\
         f 1/1 2/2 3/3\nusemtl b\nf 3/3 2/2 1/1\n",
    );
    let scene = vrpt::scene::load(&d.join("s.obj")).unwrap();
    assert_eq!(
        scene.textures.textures.len(),
        2,
        "t.png as colour and as opacity"
    );
    let (a, b) = (&scene.materials[0].maps, &scene.materials[1].maps);
    let (ka, kb) = (a.kd.unwrap(), b.kd.unwrap());
    assert_eq!(ka.index, kb.index);
    assert_eq!(
        (ka.scale, ka.offset),
        (Vec2::new(2.0, 3.0), Vec2::new(0.5, 0.25))
    );
    assert_eq!((kb.scale, kb.offset), (Vec2::ONE, Vec2::ZERO));
    assert_ne!(b.opacity.unwrap().index, kb.index);
    assert!(
        scene.warnings.iter().any(|w| w.contains("-clamp")),
        "{:?}",
        scene.warnings
    );
    // the texture multiplies Kd: sRGB 128 → 0.2158
    let s = vrpt::scene::SurfacePoint {
        p: Vec3::ZERO,
        ng: Vec3::Z,
        ns: Vec3::Z,
        uv: Vec2::splat(0.3),
        material: 0,
    };
    let kd = scene.bsdf_at(&s).eval(Vec3::Z, Vec3::Z) * std::f32::consts::PI;
    assert!(
        (kd.y - vrpt::texture::srgb_to_linear(128.0 / 255.0)).abs() < 1e-4,
        "{kd}"
    );
}

/// A scene of a floor lit by a small light above it, and between them an occluder: in
/// `cutout`, a 2 × 2 quad whose `map_d` is opaque on its left half (a 64 × 1 RGBA texture,
/// alpha 255 on columns 0..32, 0 on 32..64: bilinear alpha crosses 0.5 exactly at the middle);
/// otherwise the left half as real geometry (without the map). Seen from above, both scenes have the same
/// expected image: the opaque half itself and its shadow.
fn occluder_scene(dir: &Path, cutout: bool) -> vrpt::scene::Scene {
    png(&dir.join("half.png"), 64, 1, |x, _| {
        [200, 200, 200, if x < 32 { 255 } else { 0 }]
    });
    let map_d = if cutout { "map_d half.png\n" } else { "" };
    write(
        dir,
        "s.mtl",
        &format!(
            "newmtl floor\nKd 0.6 0.6 0.6\nnewmtl occ\nKd 0.3 0.3 0.3\n{map_d}\
             newmtl light\nKd 0 0 0\nKe 20 20 20\n"
        ),
    );
    let x1 = if cutout { 1.0 } else { 0.0 };
    let obj = format!(
        "mtllib s.mtl\n\
         v -3 0 -3\nv 3 0 -3\nv 3 0 3\nv -3 0 3\n\
         v -1 1 -1\nv {x1} 1 -1\nv {x1} 1 1\nv -1 1 1\n\
         v -0.3 2 -0.3\nv 0.3 2 -0.3\nv 0.3 2 0.3\nv -0.3 2 0.3\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
         usemtl floor\nf 1 4 3\nf 1 3 2\n\
         usemtl occ\nf 5/1 8/4 7/3\nf 5/1 7/3 6/2\n\
         usemtl light\nf 9 10 11\nf 9 11 12\n"
    );
    write(dir, "s.obj", &obj);
    write(
        dir,
        "scene.toml",
        "obj = \"s.obj\"\n[camera]\neye = [0, 6, 0]\ntarget = [0, 0, 0]\nup = [0, 0, -1]\nfov = 50\n\
         [environment]\nradiance = [0, 0, 0]\n",
    );
    vrpt::scene::load(dir).unwrap()
}

/// The cutout's shadow and image are those of its opaque half as geometry: region means (a
/// 4 × 4 grid of 8 × 8-pixel regions, 32 × 32 pixels, 512 spp, independent samples, MIS) agree
/// within z = Šidák 10⁻³ over 16 regions × 3 channels, σ² from both films' variance of the mean
/// (honest for independent samples; every region's mean averages 32,768 samples of a direct
/// light that NEE samples, so it is near normal). And the test has power: the floor under the
/// opaque half (left) is darker than under the clear half (right) by many σ.
#[test]
fn a_cutout_casts_exactly_the_shadow_of_its_opaque_half() {
    let (da, db) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (cut, geo) = (
        occluder_scene(da.path(), true),
        occluder_scene(db.path(), false),
    );
    let settings = |seed: u64| RenderSettings {
        width: 32,
        height: 32,
        spp: 512,
        max_depth: 3,
        strategy: Strategy::parse("independent+phong+mis").unwrap(),
        seed: common::seed(seed),
        ..Default::default()
    };
    let (a, _) = common::render_quiet(&cut, &settings(1));
    let (b, _) = common::render_quiet(&geo, &settings(2));
    let region = |f: &vrpt::film::Film, rx: u32, ry: u32| {
        let (mut m, mut v) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for y in ry * 8..ry * 8 + 8 {
            for x in rx * 8..rx * 8 + 8 {
                let i = f.index(x, y);
                m += f.mean(i);
                v += f.variance_of_mean(i);
            }
        }
        (m / 64.0, v / 4096.0)
    };
    let z = normal_critical_value(sidak(1e-3, 16 * 3));
    for ry in 0..4 {
        for rx in 0..4 {
            let ((ma, va), (mb, vb)) = (region(&a, rx, ry), region(&b, rx, ry));
            for c in 0..3 {
                let zc = (ma[c] - mb[c]) / (va[c] + vb[c]).sqrt().max(1e-12);
                assert!(
                    zc.abs() <= z,
                    "region ({rx},{ry}): cutout {} vs geometry {} (z {zc:.2})",
                    ma[c],
                    mb[c]
                );
            }
        }
    }
    // power: the camera looks down −y, +x to the right of the image; the outer columns of
    // regions see the floor beside the occluder (|x| > 1.4), the left one partly in the left
    // half's shadow (which reaches x = −2 from the light at twice the occluder's height), the
    // right one lit through the clear half
    let (left, vl) = region(&a, 0, 1);
    let (right, vr) = region(&a, 3, 1);
    let gap = (right.x - left.x) / (vl.x + vr.x).sqrt();
    assert!(
        gap > 10.0,
        "no shadow? left {} right {} (gap {gap:.1} σ)",
        left.x,
        right.x
    );
}

/// Bump and normal maps on a unit quad in the plane z = 0 (normal +z, u along +x, v along +y):
/// - a height map rising linearly in u (texel x of 64 holds 4x/255, so ∂h/∂u = 64·4/255 by the
///   central difference over one texel) with `-bm m` tilts the normal to
///   `normalize(−m·∂h/∂u, 0, 1)`;
/// - a normal map of constant colour (255, 128, 128) (n_ts ≈ (1, 0, 0)) turns it to +u, which
///   the two-sided rule keeps only while it stays above the surface: (191, 128, 255) tilts it
///   to `normalize(0.5, 0, 1)`.
#[test]
fn bump_and_normal_maps_tilt_the_shading_normal() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    png(&d.join("ramp.png"), 64, 4, |x, _| {
        let h = (4 * x) as u8;
        [h, h, h, 255]
    });
    png(&d.join("n.png"), 4, 4, |_, _| [191, 128, 255, 255]);
    write(
        d,
        "s.mtl",
        "newmtl bumped\nKd 0.5 0.5 0.5\nbump -bm 0.1 ramp.png\n\
         newmtl mapped\nKd 0.5 0.5 0.5\nnorm n.png\n",
    );
    write(
        d,
        "s.obj",
        "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\nv 3 1 0\nv 2 1 0\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
         usemtl bumped\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\nusemtl mapped\nf 5/1 6/2 7/3\nf 5/1 7/3 8/4\n",
    );
    let scene = vrpt::scene::load(&d.join("s.obj")).unwrap();
    let normal_at = |x: f32, y: f32| {
        let hit = scene
            .accel
            .intersect(Vec3::new(x, y, 1.0), DOWN_Z, f32::INFINITY)
            .unwrap();
        scene.surface(&hit).ns
    };
    let slope = 64.0 * 4.0 / 255.0;
    let want = Vec3::new(-0.1 * slope, 0.0, 1.0).normalize();
    let got = normal_at(0.4, 0.5);
    assert!((got - want).length() < 1e-3, "bump: {got} vs {want}");
    let c = |b: u8| b as f32 / 255.0 * 2.0 - 1.0;
    let want = Vec3::new(c(191), c(128), c(255)).normalize();
    let got = normal_at(2.5, 0.5);
    assert!((got - want).length() < 1e-3, "normal map: {got} vs {want}");
}

/// The shipped textured scene loads its four PNGs (the fence's twice: colour and opacity),
/// renders without non-finite samples, and its fence is cut out: a camera ray through a gap of
/// the lattice passes the fence's plane.
#[test]
fn the_shipped_textured_scene_renders() {
    let scene = common::shipped("textured");
    assert_eq!(scene.textures.textures.len(), 5);
    let s = RenderSettings {
        width: 32,
        height: 24,
        spp: 4,
        ..RenderSettings::for_scene(&scene)
    };
    let (_, stats) = common::render_quiet(&scene, &s);
    assert_eq!(stats.nonfinite, 0);
    // the fence spans x ∈ [−1.5, 1.5], y ∈ [0, 2] at z = −2, its uv u = 1.5 (x + 1.5)/3, and
    // its lattice is opaque where the texel column or row mod 8 is below 2 (64 texels per
    // unit of uv): through texel (5, 60) of the first tile (bottom row 63 − 60 = 3 → v ≈ 0.06)
    let u = (5.5 / 64.0) / 1.5 * 3.0 - 1.5;
    let v = (1.0 - 60.5 / 64.0) * 2.0;
    let origin = Vec3::new(u, v, 0.0);
    let mut stack = vrpt::accel::TraceStack::default();
    let hit = scene
        .intersect(&mut stack, origin, DOWN_Z, f32::INFINITY)
        .unwrap();
    assert!(hit.t > 2.5, "stopped at t = {} by the fence's gap", hit.t);
    // and a bar (texel column 0) stops it
    let origin = Vec3::new((0.5 / 64.0) / 1.5 * 3.0 - 1.5, v, 0.0);
    let hit = scene
        .intersect(&mut stack, origin, DOWN_Z, f32::INFINITY)
        .unwrap();
    assert!((hit.t - 2.0).abs() < 1e-3, "the bar: t = {}", hit.t);
}

/// A scene keeps its triangles' texture coordinates only where a material reads them: the
/// textured scene keeps one triple a triangle (the fence's cutout reads them: the test above),
/// the Cornell box, whose materials have no map, keeps none, and its shading data is the
/// 56-byte record a triangle and nothing more.
#[test]
fn texture_coordinates_are_kept_only_where_a_map_reads_them() {
    let textured = common::shipped("textured");
    assert_eq!(textured.uvs.len(), textured.triangle_count());
    assert!(textured
        .uvs
        .iter()
        .any(|t| t.iter().any(|uv| *uv != Vec2::ZERO)));
    let cornell = common::shipped("cornell-box");
    assert!(cornell.uvs.is_empty());
    assert_eq!(cornell.memory_bytes().1, 56 * cornell.triangle_count());
}

/// Rays along the axes, with −0.0 or +0.0 in their zero components, find what testing every
/// triangle finds, in the textured scene (whose quads lie in axis planes: flat boxes). obvhs
/// inverted −0.0 as −1/ε but ordered slabs by `x < 0.0`: before `accel::positive_zeros`, the
/// ray (−0.0, −0.0, −1) through the fence missed everything.
#[test]
fn axis_rays_with_signed_zeros_hit_what_brute_force_hits() {
    let scene = common::shipped("textured");
    let mut checked = 0;
    for k in 0..200 {
        let (a, b) = ((k % 20) as f32 / 20.0, (k / 20) as f32 / 10.0);
        let origin = Vec3::new(-4.0 + 8.0 * a, 0.05 + 3.5 * b, 2.0);
        for dir in [
            -Vec3::Z,
            Vec3::new(0.0, 0.0, -1.0),
            -Vec3::Y,
            Vec3::new(-0.0, -1.0, 0.0),
        ] {
            let bvh = scene.accel.intersect(origin, dir, f32::INFINITY);
            let brute = scene
                .accel
                .intersect_brute_force(origin, dir, f32::INFINITY);
            assert_eq!(bvh.map(|h| h.t), brute.map(|h| h.t), "{origin} {dir:?}");
            checked += brute.is_some() as usize;
        }
    }
    assert!(checked > 300, "{checked} rays hit");
}
