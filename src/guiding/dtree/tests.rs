//! The directional quadtree's tests: refinement, the box filter, sampling against the pdf,
//! and MIS compensation.

use super::*;
use crate::guiding::ENERGY_FRACTION;

/// Refinement splits where the energy is, and the refined tree's records build sums that
/// add up.
#[test]
fn refine_and_build() {
    let mut t = DTree::default();
    for k in 0..1000 {
        let p = Vec2::new(0.1 + 0.001 * (k % 10) as f32, 0.8);
        t.record(p, 1.0);
    }
    t.record(Vec2::new(0.9, 0.1), 1.0);
    t.build();
    assert_eq!(t.total(), 1001.0);
    let r = t.refined(ENERGY_FRACTION);
    assert!(r.node_count() > 4, "{}", r.node_count());
    assert!(r.depth() >= 4);
    assert_eq!(r.total(), 0.0);
}

/// A record's box keeps all its value next to `φ = 0` (v wraps) and next to a pole (u
/// ends): clipped, as before issue 46, a record at a corner kept a quarter of it.
#[test]
fn a_box_record_keeps_its_value_at_the_edges() {
    let t = learned();
    for p in [
        Vec2::new(0.5, 0.0001),
        Vec2::new(0.5, 0.9999),
        Vec2::new(0.0001, 0.5),
        Vec2::new(0.9999, 0.0001),
        Vec2::new(0.1, 0.8),
        Vec2::new(0.10005, 0.80005),
    ] {
        let mut r = t.refined(ENERGY_FRACTION);
        r.record_box(p, 2.0);
        r.build();
        assert!((r.total() - 2.0).abs() < 1e-5, "{p}: {}", r.total());
    }
    // wrapped: a record at v = 0⁺ gives its neighbour across v = 1 as much as the one it lies in
    let mut r = DTree::default();
    r.record_box(Vec2::new(0.6, 0.0), 1.0);
    r.build();
    let (below, above) = (
        r.pdf_canonical(Vec2::new(0.6, 0.99)),
        r.pdf_canonical(Vec2::new(0.6, 0.01)),
    );
    assert!(
        below > 0.0 && (below - above).abs() < 1e-6,
        "{below} {above}"
    );
}

/// A tree refined where energy was recorded (several levels deep in one corner).
fn learned() -> DTree {
    let mut t = DTree::default();
    for k in 0..2000 {
        let p = Vec2::new(
            0.1 + 0.0001 * (k % 97) as f32,
            0.8 + 0.0001 * (k % 13) as f32,
        );
        t.record(p, 1.0);
    }
    t.record(Vec2::new(0.9, 0.1), 5.0);
    t.build();
    let mut r = t.refined(ENERGY_FRACTION);
    for k in 0..5000u32 {
        let p = Vec2::new(
            (k as f32 * 0.618_034).fract() * 0.3,
            0.6 + (k as f32 * 0.414_213_6).fract() * 0.3,
        );
        r.record(p, 1.0 + (k % 7) as f32);
    }
    r.record(Vec2::new(0.7, 0.2), 100.0);
    r.build();
    r
}

/// The directional box filter keeps a record's energy whole when its box lies inside the
/// square (the overlaps of a box with the leaves it covers sum to its area), and spreads
/// it over more than one leaf where the box straddles leaves.
#[test]
fn the_box_filter_keeps_the_energy() {
    let mut t = learned().refined(ENERGY_FRACTION);
    assert!(t.depth() > 3);
    let mut spread = 0;
    for (k, p) in [
        (0.11f32, 0.81f32),
        (0.2, 0.7),
        (0.5, 0.5),
        (0.26, 0.74),
        (0.7, 0.3),
    ]
    .into_iter()
    .enumerate()
    {
        let before: Vec<[f32; 4]> = t.nodes.iter().map(|n| n.sum).collect();
        t.record_box(Vec2::new(p.0, p.1), 1.0);
        let (mut added, mut cells) = (0.0f64, 0);
        for (n, b) in t.nodes.iter().zip(&before) {
            for (now, was) in n.sum.iter().zip(b) {
                let d = (now - was) as f64;
                if d != 0.0 {
                    added += d;
                    cells += 1;
                }
            }
        }
        assert!(
            (added - 1.0).abs() < 1e-5,
            "box {k} at {p:?}: added {added}"
        );
        spread += (cells > 1) as u32;
    }
    assert!(spread >= 2, "boxes straddling leaves: {spread}");
}

/// MIS compensation by hand: a tree of total 8 with energy 4 in a sixteenth of the square
/// (density 8 against the mean 1) and 2, 1, 1 in three quarters (densities 1, ½, ½) keeps
/// `4 − 8/16 = 3.5` in the sixteenth and nothing elsewhere, so its sampling density is 16
/// there and 0 elsewhere; the learned density read back is 8 there and the mean, 1, where
/// the compensated tree is zero. A uniform tree has nothing above its mean and stays as it is.
#[test]
fn compensation_subtracts_the_mean_density() {
    let t = DTree::from_nodes(&[
        ([0.0, 2.0, 1.0, 1.0], [1, 0, 0, 0]),
        ([4.0, 0.0, 0.0, 0.0], [0; 4]),
    ]);
    assert_eq!(t.total(), 8.0);
    let c = t.compensated();
    assert_eq!(c.total(), 3.5);
    let (hot, warm, cold) = (
        Vec2::new(0.1, 0.1),
        Vec2::new(0.75, 0.25),
        Vec2::new(0.25, 0.75),
    );
    assert_eq!(t.pdf_canonical(hot), 8.0);
    assert_eq!(c.pdf_canonical(hot), 16.0);
    assert_eq!(c.pdf_canonical(warm), 0.0);
    assert_eq!(c.pdf_canonical(cold), 0.0);
    assert_eq!(c.learned_density(c.pdf_canonical(hot)), 8.0);
    assert_eq!(c.learned_density(0.0), 1.0);
    assert_eq!(c.radiance(), t.radiance());
    let uniform = DTree::from_nodes(&[([1.0; 4], [0; 4])]);
    assert_eq!(uniform.compensated(), uniform);
    assert_eq!(uniform.learned_density(1.0), 1.0);
}

/// On a learned tree many levels deep, the compensated tree read back gives the learned
/// density wherever it lies above the mean and the mean elsewhere: `max(p, 1)`, so each
/// leaf's area was found right at every depth.
#[test]
fn compensation_reads_back_the_learned_density_above_its_mean() {
    let t = learned();
    let c = t.compensated();
    assert!(c.total() > 0.0 && c.total() < t.total());
    let (mut above, mut below) = (0, 0);
    for i in 0..256 {
        for j in 0..256 {
            let p = Vec2::new((i as f32 + 0.5) / 256.0, (j as f32 + 0.5) / 256.0);
            let (want, got) = (
                t.pdf_canonical(p).max(1.0),
                c.learned_density(c.pdf_canonical(p)),
            );
            assert!(
                (got - want).abs() <= 1e-3 * want,
                "{p}: {got} against {want}"
            );
            if c.pdf_canonical(p) > 0.0 {
                above += 1;
            } else {
                below += 1;
            }
        }
    }
    assert!(above > 0 && below > 0, "{above} {below}");
}

/// The density a sample's descent returns is the density the tree gives its point, and a
/// compensated tree's samples land only where its density is positive.
#[test]
fn a_sample_carries_its_own_pdf() {
    let t = learned();
    assert!(t.total() > 0.0 && t.depth() > 3);
    let c = t.compensated();
    for i in 0..4096u32 {
        let u = Vec2::new(
            (i as f32 * 0.754_877_7 + 0.1).fract(),
            (i as f32 * 0.569_840_3 + 0.3).fract(),
        );
        let (p, pdf) = c.sample_canonical_pdf(u);
        assert!(
            pdf > 0.0 && (pdf - c.pdf_canonical(p)).abs() <= 1e-4 * pdf,
            "{p} {pdf}"
        );
    }
    for i in 0..4096u32 {
        let u = Vec2::new(
            (i as f32 * 0.754_877_7 + 0.1).fract(),
            (i as f32 * 0.569_840_3 + 0.3).fract(),
        );
        let (c, pdf) = t.sample_canonical_pdf(u);
        let want = t.pdf_canonical(c);
        assert!(
            (pdf - want).abs() <= 1e-4 * want,
            "u {u}: point {c}, pdf {pdf}, tree says {want}"
        );
    }
}
