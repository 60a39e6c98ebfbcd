//! Procedural test meshes: grids, tubes, bars, spheres, a bend deformer, and rigs that provoke
//! two equilibria (a turning head, a buckling sheet).
//!
//! All generated meshes are consistently oriented with outward normals (for closed ones).

use super::{Point, ShapeSet, TriMesh};

/// A flat `nx × ny` grid of quads (each split into two triangles) spanning `[0, sx] × [0, sy]`
/// in the `z = 0` plane; `(nx + 1)(ny + 1)` vertices, normals along `+z`.
pub fn grid(nx: usize, ny: usize, sx: f64, sy: f64) -> TriMesh {
    let nx = nx.max(1);
    let ny = ny.max(1);
    let mut p = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            p.push([sx * i as f64 / nx as f64, sy * j as f64 / ny as f64, 0.0]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut t = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::new(p, t)
}

/// A tube along `+x` from `x = 0` to `x = length`, `around` vertices per ring and `along`
/// segments, radius `radius`. With `capped`, each end gets a centre vertex and a triangle fan,
/// making the mesh closed.
pub fn tube(radius: f64, length: f64, around: usize, along: usize, capped: bool) -> TriMesh {
    let around = around.max(3);
    let along = along.max(1);
    let mut p = Vec::new();
    for j in 0..=along {
        let x = length * j as f64 / along as f64;
        for i in 0..around {
            let a = std::f64::consts::TAU * i as f64 / around as f64;
            p.push([x, radius * a.cos(), radius * a.sin()]);
        }
    }
    let id = |i: usize, j: usize| (j * around + i % around) as u32;
    let mut t = Vec::new();
    for j in 0..along {
        for i in 0..around {
            // Outward normals: the ring angle increases counter-clockwise seen from +x.
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
        }
    }
    if capped {
        let c0 = p.len() as u32;
        p.push([0.0, 0.0, 0.0]);
        let c1 = p.len() as u32;
        p.push([length, 0.0, 0.0]);
        for i in 0..around {
            t.push([c0, id(i + 1, 0), id(i, 0)]);
            t.push([c1, id(i, along), id(i + 1, along)]);
        }
    }
    TriMesh::new(p, t)
}

/// A closed rectangular bar along `+x`: a capped tube with a square cross-section of side
/// `width` (`4 × per_side` vertices per ring).
pub fn bar(length: f64, width: f64, per_side: usize, along: usize) -> TriMesh {
    let per_side = per_side.max(1);
    let n = 4 * per_side;
    let mut m = tube(1.0, length, n, along, true);
    let h = 0.5 * width;
    // Map the circle of each ring onto the square of half-width h (same parameter spacing).
    for v in m.positions.iter_mut() {
        let (y, z) = (v[1], v[2]);
        if y == 0.0 && z == 0.0 {
            continue; // cap centres
        }
        let a = z.atan2(y).rem_euclid(std::f64::consts::TAU);
        let s = a / std::f64::consts::TAU * 4.0; // 0..4 around the square
        let side = s.floor() as i32 % 4;
        let f = s - s.floor();
        let (ny, nz) = match side {
            0 => (h, -h + 2.0 * h * f),
            1 => (h - 2.0 * h * f, h),
            2 => (-h, h - 2.0 * h * f),
            _ => (-h + 2.0 * h * f, -h),
        };
        // Rotate by 45° so that the parameter origin sits at a corner-free spot.
        v[1] = ny;
        v[2] = nz;
    }
    m
}

/// A UV sphere of radius `radius` with `lat` latitude bands and `lon` longitude segments.
pub fn uv_sphere(radius: f64, lat: usize, lon: usize) -> TriMesh {
    let lat = lat.max(2);
    let lon = lon.max(3);
    let mut p = vec![[0.0, 0.0, radius]];
    for j in 1..lat {
        let th = std::f64::consts::PI * j as f64 / lat as f64;
        for i in 0..lon {
            let ph = std::f64::consts::TAU * i as f64 / lon as f64;
            p.push([
                radius * th.sin() * ph.cos(),
                radius * th.sin() * ph.sin(),
                radius * th.cos(),
            ]);
        }
    }
    p.push([0.0, 0.0, -radius]);
    let south = (p.len() - 1) as u32;
    let id = |i: usize, j: usize| (1 + (j - 1) * lon + i % lon) as u32;
    let mut t = Vec::new();
    for i in 0..lon {
        t.push([0, id(i, 1), id(i + 1, 1)]);
    }
    for j in 1..lat - 1 {
        for i in 0..lon {
            t.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    for i in 0..lon {
        t.push([south, id(i + 1, lat - 1), id(i, lat - 1)]);
    }
    TriMesh::new(p, t)
}

/// Bends the part of a shape with `x > start` about an axis parallel to `z`, so that the
/// centre line `y = z = 0` keeps its length and the far end turns by `angle` radians over the
/// remaining length `bent_length`. Points with `x ≤ start` do not move.
pub fn bend(positions: &[Point], start: f64, bent_length: f64, angle: f64) -> Vec<Point> {
    if angle.abs() < 1e-12 {
        return positions.to_vec();
    }
    let r = bent_length / angle;
    positions
        .iter()
        .map(|&[x, y, z]| {
            if x <= start {
                return [x, y, z];
            }
            let s = (x - start).min(bent_length);
            let phi = s / r;
            let (sin, cos) = phi.sin_cos();
            let mut q = [start + (r - y) * sin, r - (r - y) * cos, z];
            // Beyond the bent part, continue straight along the end tangent.
            let extra = (x - start) - s;
            if extra > 0.0 {
                q[0] += extra * cos;
                q[1] += extra * sin;
            }
            q
        })
        .collect()
}

/// Rotates points about the axis through `center` along unit `axis` by `angle` radians.
pub fn rotate(positions: &[Point], center: Point, axis: Point, angle: f64) -> Vec<Point> {
    let r = nalgebra::Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(nalgebra::Vector3::from(axis)),
        angle,
    );
    let c = nalgebra::Vector3::from(center);
    positions
        .iter()
        .map(|p| {
            let q = r * (nalgebra::Vector3::from(*p) - c) + c;
            [q.x, q.y, q.z]
        })
        .collect()
}

/// A rig that provokes two nearby equilibria (issue 54): a capped neck along `+x` (length 2,
/// radius 0.15, 16 × 40) with a head at its end (a nose on `+y` makes it asymmetric), and one
/// target where the head turns by `turn_deg` about the neck's axis and rolls by `roll_deg`
/// about `z`, both eased in over the neck (`0.6 ≤ x ≤ 1.4`). Near 180° a turn either way fits
/// the blended lengths about equally.
pub fn turning_head_rig(turn_deg: f64, roll_deg: f64) -> ShapeSet {
    let mut m = tube(0.15, 2.0, 16, 40, true);
    for p in &mut m.positions {
        if p[0] > 1.5 && p[1] > 0.0 {
            p[1] *= 1.0 + 0.8 * ((p[0] - 1.5) / 0.5).min(1.0);
        }
    }
    let ease = |x: f64| {
        let t = ((x - 0.6) / 0.8).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    let target = m
        .positions
        .iter()
        .map(|&p| {
            let s = ease(p[0]);
            let c = [0.6, 0.0, 0.0];
            let q = rotate(&[p], c, [1.0, 0.0, 0.0], (turn_deg * s).to_radians())[0];
            rotate(&[q], c, [0.0, 0.0, 1.0], (roll_deg * s).to_radians())[0]
        })
        .collect();
    let base = m.positions.clone();
    ShapeSet::new(m, vec![("rest".into(), base), ("turn".into(), target)])
        .expect("the generated rig is valid")
}

/// A rig whose blend can buckle either way (issue 54): a thin sheet (2 × 0.6, 32 × 8 cells)
/// in the `xy` plane, and one target where it arches into a half circle over `+z`, each
/// line along `x` keeping its length.
pub fn buckling_sheet_rig() -> ShapeSet {
    let (l, theta) = (2.0, std::f64::consts::PI);
    let m = grid(32, 8, l, 0.6);
    let r = l / theta;
    let target = m
        .positions
        .iter()
        .map(|&[x, y, _]| {
            let phi = (x / l - 0.5) * theta;
            [
                l / 2.0 + r * phi.sin(),
                y,
                r * phi.cos() - r * (theta / 2.0).cos(),
            ]
        })
        .collect();
    let base = m.positions.clone();
    ShapeSet::new(m, vec![("flat".into(), base), ("arch".into(), target)])
        .expect("the generated rig is valid")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{validate, Topology};

    #[test]
    fn enclosed_volume_of_a_bar_is_exact_and_flips_with_orientation() {
        let m = bar(4.0, 0.6, 2, 16);
        let v = crate::mesh::enclosed_volume(&m.positions, &m.triangles);
        assert!((v - 4.0 * 0.6 * 0.6).abs() < 1e-12, "{v}");
        // Moved away from the origin: the same volume (closed surface).
        let moved: Vec<_> = m
            .positions
            .iter()
            .map(|p| [p[0] + 7.0, p[1] - 3.0, p[2] + 2.0])
            .collect();
        let w = crate::mesh::enclosed_volume(&moved, &m.triangles);
        assert!((w - v).abs() < 1e-10, "{w} vs {v}");
        let flipped: Vec<[u32; 3]> = m.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect();
        assert!((crate::mesh::enclosed_volume(&m.positions, &flipped) + v).abs() < 1e-12);
    }

    #[test]
    fn generated_meshes_are_valid_and_oriented() {
        for (m, closed) in [
            (grid(4, 3, 1.0, 1.0), false),
            (tube(0.5, 4.0, 12, 10, false), false),
            (tube(0.5, 4.0, 12, 10, true), true),
            (bar(4.0, 1.0, 3, 12), true),
            (uv_sphere(1.0, 8, 12), true),
        ] {
            let r = validate(&m).unwrap();
            assert!(r.warnings.is_empty(), "{:?}", r.warnings);
            let t = Topology::new(m.num_vertices(), &m.triangles);
            assert_eq!(t.is_closed(), closed);
            assert!(t.is_consistently_oriented());
            if closed {
                // Outward orientation: positive signed volume.
                assert!(crate::mesh::enclosed_volume(&m.positions, &m.triangles) > 0.0);
            }
        }
    }

    #[test]
    fn bend_keeps_centre_line_length() {
        let line: Vec<Point> = (0..=100).map(|i| [i as f64 * 0.04, 0.0, 0.0]).collect();
        let b = bend(&line, 2.0, 2.0, 2.0);
        let len: f64 = b
            .windows(2)
            .map(|w| crate::mesh::norm(crate::mesh::sub(w[1], w[0])))
            .sum();
        // The chords of a polyline on an arc are slightly shorter than the arc.
        assert!((len - 4.0).abs() < 2e-4, "{len}");
        assert_eq!(b[10], line[10]);
    }
}
