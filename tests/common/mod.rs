//! Helpers shared by the integration tests: scenes written on the fly, small renders.
#![allow(dead_code)]

use glam::Vec3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use vrpt::film::Film;
use vrpt::render::{render, NoProgress, RenderSettings, RenderStats};
use vrpt::scene::Scene;

/// The shipped Cornell box.
pub fn cornell_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box")
}

/// The folder of a shipped scene.
pub fn shipped_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// Load a shipped scene by folder name.
pub fn shipped(name: &str) -> Scene {
    vrpt::scene::load(&shipped_path(name)).unwrap()
}

/// Write `text` to `dir/name` and return the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// An icosphere (subdivided icosahedron) of radius `r` as OBJ text, faces wound outward, no
/// normals (so shading uses the flat geometric normals and the mesh is exactly convex).
pub fn icosphere_obj(r: f32, subdivisions: u32, material: &str) -> String {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut cache = std::collections::HashMap::new();
        let mut mid = |a: usize, b: usize, v: &mut Vec<Vec3>| {
            *cache.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a] + v[b]) * 0.5).normalize());
                v.len() - 1
            })
        };
        let mut nf = Vec::new();
        for [a, b, c] in f {
            let (ab, bc, ca) = (mid(a, b, &mut v), mid(b, c, &mut v), mid(c, a, &mut v));
            nf.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    let mut s = String::new();
    for p in &v {
        writeln!(s, "v {} {} {}", p.x * r, p.y * r, p.z * r).unwrap();
    }
    writeln!(s, "usemtl {material}").unwrap();
    for [a, b, c] in &f {
        // make the winding outward
        let n = (v[*b] - v[*a]).cross(v[*c] - v[*a]);
        if n.dot(v[*a]) >= 0.0 {
            writeln!(s, "f {} {} {}", a + 1, b + 1, c + 1).unwrap();
        } else {
            writeln!(s, "f {} {} {}", a + 1, c + 1, b + 1).unwrap();
        }
    }
    s
}

/// Render quietly.
pub fn render_quiet(scene: &Scene, settings: &RenderSettings) -> (Film, RenderStats) {
    render(scene, settings, &NoProgress).unwrap()
}
