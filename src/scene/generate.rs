//! Generated meshes of any size, for benchmarks, scaling measurements and tests:
//! - [`terrain`]: an n×n grid of quads (2n² triangles) over `[−1, 1]²` in x–z with a smooth
//!   multi-octave height field, faces wound so their normals point up (+y);
//! - [`icosphere`]: a subdivided icosahedron on the unit sphere (20·4^k triangles), faces wound
//!   outward.

use glam::Vec3;
use std::collections::HashMap;

/// An n×n-quad height field: 2n² triangles, normals up.
pub fn terrain(n: u32) -> Vec<[Vec3; 3]> {
    let n = n.max(1);
    let h = |x: f32, z: f32| {
        0.15 * (3.1 * x).sin() * (2.3 * z).cos()
            + 0.05 * (11.0 * x + 1.0).sin() * (13.0 * z).sin()
            + 0.01 * (47.0 * x).cos() * (41.0 * z + 2.0).sin()
    };
    let p = |i: u32, j: u32| {
        let x = -1.0 + 2.0 * i as f32 / n as f32;
        let z = -1.0 + 2.0 * j as f32 / n as f32;
        Vec3::new(x, h(x, z), z)
    };
    let mut tris = Vec::with_capacity(2 * (n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            // counter-clockwise seen from +y
            tris.push([a, d, b]);
            tris.push([b, d, c]);
        }
    }
    tris
}

/// The number of quads per side for a terrain of about `triangles` triangles.
pub fn terrain_side_for(triangles: usize) -> u32 {
    ((triangles as f64 / 2.0).sqrt().round() as u32).max(1)
}

/// A unit icosphere with `subdivisions` levels: 20·4^k triangles, wound outward.
pub fn icosphere(subdivisions: u32) -> Vec<[Vec3; 3]> {
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
        let mut cache: HashMap<(usize, usize), usize> = HashMap::new();
        let mut mid = |a: usize, b: usize, v: &mut Vec<Vec3>| {
            *cache.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a] + v[b]) * 0.5).normalize());
                v.len() - 1
            })
        };
        let mut nf = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let (ab, bc, ca) = (mid(a, b, &mut v), mid(b, c, &mut v), mid(c, a, &mut v));
            nf.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    f.iter()
        .map(|&[a, b, c]| {
            let n = (v[b] - v[a]).cross(v[c] - v[a]);
            if n.dot(v[a]) >= 0.0 {
                [v[a], v[b], v[c]]
            } else {
                [v[a], v[c], v[b]]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_windings() {
        let t = terrain(10);
        assert_eq!(t.len(), 200);
        assert!(t.iter().all(|[a, b, c]| (*b - *a).cross(*c - *a).y > 0.0));
        assert_eq!(terrain_side_for(1_000_000), 707);
        let s = icosphere(2);
        assert_eq!(s.len(), 320);
        assert!(s
            .iter()
            .all(|[a, b, c]| (*b - *a).cross(*c - *a).dot(*a) > 0.0));
    }
}
