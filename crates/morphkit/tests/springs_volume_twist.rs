//! Volume under a large twist (issue 40): a closed shape twisted 180° about its long axis and
//! blended at α = ¼, ½, ¾ with the default lattice interior keeps the interpolated volume
//! $\bar V(\alpha) = (1 - \alpha) V_0 + \alpha V_1$ within 2 % (the rest and the twisted target
//! differ by 0.25 % on Spot, 1.5 % on the generated cylinder). Interpolated rest lengths of
//! springs oblique to a twist are too long, surface and interior alike, so springs alone
//! inflate the blend (+6.1 % on Spot with the lattice, +6.7 % with surface springs); the volume
//! term on the interior's tetrahedra and shell holds it (docs/fidelity.md, "Volume under
//! twist"). The deviation at α = ¼, ¾ is bounded by 1.5 %: the excess of the blended rest
//! lengths grows like α(1 − α), ¾ of its value at ½.

mod common;

use morphkit::mesh::{bounding_box, enclosed_volume as volume, generate, Point, ShapeSet};
use morphkit::springs::{
    linear_blend, AnchorOptions, BlendOptions, InteriorMode, InteriorOptions, PhysicalBlend,
    VolumetricBlend, Weights,
};

/// `p` twisted about the line parallel to x through its bounding box's centre, by an angle
/// growing linearly from 0 at the smallest x to `deg` at the largest.
fn twist(p: &[Point], deg: f64) -> Vec<Point> {
    let (lo, hi) = bounding_box(p);
    let (cy, cz) = (0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    p.iter()
        .map(|&[x, y, z]| {
            let a = deg.to_radians() * (x - lo[0]) / (hi[0] - lo[0]);
            let (s, c) = a.sin_cos();
            let (y, z) = (y - cy, z - cz);
            [x, cy + c * y - s * z, cz + s * y + c * z]
        })
        .collect()
}

fn twisted(positions: Vec<Point>, triangles: Vec<[u32; 3]>) -> ShapeSet {
    let t = twist(&positions, 180.0);
    let m = morphkit::mesh::TriMesh::new(positions.clone(), triangles);
    ShapeSet::new(m, vec![("base".into(), positions), ("twisted".into(), t)]).unwrap()
}

fn lattice(density: f64) -> InteriorOptions {
    InteriorOptions {
        mode: InteriorMode::Lattice,
        density,
        ..Default::default()
    }
}

/// Signed relative deviations (V − V̄)/V̄ at α = ¼, ½, ¾ of the volumetric blend, and of
/// surface springs alone at α = ½.
fn deviations(s: &ShapeSet, interior: &InteriorOptions) -> ([f64; 3], f64) {
    let t = s.triangles();
    let (v0, v1) = (volume(s.positions(0), t), volume(s.positions(1), t));
    let rel = |p: &[Point], a: f64| {
        let target = (1.0 - a) * v0 + a * v1;
        (volume(p, t) - target) / target
    };
    let mut v = VolumetricBlend::new(
        s,
        &BlendOptions::default(),
        interior,
        &AnchorOptions::default(),
    )
    .unwrap();
    assert!(v.report().interior_vertices > 0, "{:?}", v.report());
    let out = [0.25, 0.5, 0.75].map(|a| {
        let r = v.solve(&Weights::Alpha(a)).unwrap();
        assert!(r.stats.converged, "α = {a}: {:?}", r.stats);
        assert_eq!(r.inversions.tetrahedra, 0, "α = {a}: {:?}", r.inversions);
        rel(&r.positions, a)
    });
    let w = Weights::Alpha(0.5);
    let surf = PhysicalBlend::new(s, &BlendOptions::default())
        .unwrap()
        .solve(&w)
        .unwrap();
    let lin = linear_blend(s, &w).unwrap();
    eprintln!(
        "α = ¼, ½, ¾: {:+.2e} {:+.2e} {:+.2e}; at ½ surface springs {:+.2e}, linear {:+.2e}",
        out[0],
        out[1],
        out[2],
        rel(&surf.positions, 0.5),
        rel(&lin, 0.5)
    );
    (out, rel(&surf.positions, 0.5))
}

fn assert_within(dev: [f64; 3], what: &str) {
    assert!(
        dev[1].abs() <= 0.02,
        "{what}: α = ½ deviation {:+.3e}",
        dev[1]
    );
    for k in [0, 2] {
        assert!(dev[k].abs() <= 0.015, "{what}: α = ¼/¾ deviation {dev:?}");
    }
}

/// A closed cylinder (radius 0.6, length 2, 24 × 16 quads, capped) twisted 180°: shear up to
/// 0.94 at its rim. Measured, α = ½: springs alone with the lattice +2.2 % (density 1) and
/// +3.2 % (density 2), surface springs +3.7 %; with the volume term 1.5e-3 and 8.5e-4.
#[test]
fn a_twisted_cylinder_keeps_its_volume_with_the_lattice() {
    let m = generate::tube(0.6, 2.0, 24, 16, true);
    let s = twisted(m.positions, m.triangles);
    for density in [1.0, 2.0] {
        let (dev, _) = deviations(&s, &lattice(density));
        assert_within(dev, &format!("cylinder, density {density}"));
        assert!(dev[1].abs() <= 5e-3, "density {density}: {dev:?}");
    }
}

/// Spot (closed, 829 vertices; long axis z turned onto x) twisted 180° from tail to head, the
/// issue's case: linear −50 %, surface springs +6.7 %, lattice springs alone +6.1 %
/// (¼: +4.5 %, ¾: +4.6 %); with the volume term +0.61 %, +0.74 %, +0.49 %.
#[test]
fn a_twisted_spot_keeps_its_volume_with_the_default_lattice() {
    let Some(f) = common::data_file("generic-meshes/spot_low_resolution.obj.gz") else {
        return common::skip("a_twisted_spot_keeps_its_volume_with_the_default_lattice");
    };
    let m = morphkit::io::read_mesh(&f).unwrap();
    let p: Vec<Point> = m.positions.iter().map(|&[x, y, z]| [z, y, -x]).collect();
    let s = twisted(p, m.triangles);
    let (dev, surf) = deviations(&s, &lattice(1.0));
    assert_within(dev, "spot");
    assert!(
        dev[1].abs() <= 0.25 * surf.abs(),
        "{dev:?} vs surface {surf}"
    );
}
