//! Rigid obstacles for the physical interaction of Ma et al. 2012, Sec. 4: a closed triangle
//! mesh or a primitive, placed in the world by a rigid transform keyframed over frames.
//!
//! - **Geometry.** Point queries are `parry3d-f64`'s: a mesh obstacle is a parry `TriMesh`
//!   built with [`TriMeshFlags::ORIENTED`], whose BVH finds the closest triangle and whose
//!   pseudo-normals decide inside from outside; primitives use parry's exact projections.
//!   A query gives the closest surface point $q$ of a point $p$ and whether $p$ is inside; the
//!   penetration depth is $\lVert p - q \rVert$ and the penetration direction $q - p$.
//! - **Primitives** are in their local frame: a sphere of `radius` at the origin; a box of full
//!   `size` centred at the origin; a cylinder of `radius` and full `height` along local `+y`,
//!   centred; a capsule of `radius` whose segment of `length` runs along local `y`, centred;
//!   a plane through the origin with its `normal` pointing out of the solid half-space.
//! - **Mesh obstacles must be closed**: an open mesh has no inside, so it is refused
//!   ([`ObstacleError::NotClosed`]) rather than treated as one-sided. It must also be
//!   consistently oriented; if it encloses a negative volume (normals inward) its triangles are
//!   flipped, so both orientations work.
//! - **Motion.** Keys give the world pose at frame numbers, strictly increasing: translation
//!   interpolated linearly, rotation by slerp ([`super::keys`]); the first key holds before it
//!   and the last after it. World $x = R\,x_\text{local} + t$.

use super::keys::{bracket, first_out_of_order, lerp, slerp};
use crate::mesh::{Point, Topology, TriMesh};
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::{Pose, Rotation, Vector};
use parry3d_f64::shape::{
    Ball, Capsule, Cuboid, Cylinder, SharedShape, TriMesh as ParryMesh, TriMeshFlags,
};

/// Why an obstacle cannot be used.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ObstacleError {
    /// The mesh has boundary or non-manifold edges, hence no inside.
    #[error("obstacle '{name}': the mesh is not closed ({open_edges} boundary or non-manifold edges, e.g. between vertices {example:?}); an open surface has no inside to collide with, so it is refused: close it (fill its holes) or use a primitive")]
    NotClosed {
        /// The obstacle.
        name: String,
        /// Count of boundary or non-manifold edges.
        open_edges: usize,
        /// One of them.
        example: [u32; 2],
    },
    /// Neighbouring triangles disagree on their orientation.
    #[error("obstacle '{name}': the mesh is not consistently oriented (neighbouring triangles face opposite ways), so its inside is undefined")]
    NotOriented {
        /// The obstacle.
        name: String,
    },
    /// A primitive's dimension is not a finite positive number (or the normal is zero).
    #[error("obstacle '{name}': {what} must be finite and positive, got {value}")]
    Dimension {
        /// The obstacle.
        name: String,
        /// Which dimension.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// Keyframes are not strictly increasing in frame.
    #[error("obstacle '{name}': key {index} is at frame {frame}, not after the previous key's frame {previous}; keyframes must be in increasing frame order")]
    KeysOutOfOrder {
        /// The obstacle.
        name: String,
        /// The offending key.
        index: usize,
        /// Its frame.
        frame: f64,
        /// The previous key's frame.
        previous: f64,
    },
    /// A key has a non-finite frame, translation or rotation.
    #[error("obstacle '{name}': key {index} has a non-finite frame, translation or rotation")]
    NonFiniteKey {
        /// The obstacle.
        name: String,
        /// The offending key.
        index: usize,
    },
    /// parry refused the mesh.
    #[error("obstacle '{name}': {cause}")]
    Build {
        /// The obstacle.
        name: String,
        /// parry's message.
        cause: String,
    },
}

/// A primitive solid, in its local frame (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub enum Primitive {
    /// A ball at the origin.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// An axis-aligned box centred at the origin.
    Box {
        /// Full edge lengths along x, y, z.
        size: [f64; 3],
    },
    /// A capped cylinder along local y, centred at the origin.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Full height.
        height: f64,
    },
    /// A capsule around a segment along local y, centred at the origin.
    Capsule {
        /// Radius.
        radius: f64,
        /// Length of the inner segment (the capsule is `length + 2 radius` long).
        length: f64,
    },
    /// The half-space below a plane through the origin.
    Plane {
        /// Outward normal (need not be unit length).
        normal: Point,
    },
}

/// The world pose of an obstacle at one frame number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidKey {
    /// Frame number (0 = first frame; fractions allowed).
    pub frame: f64,
    /// World translation $t$.
    pub translation: Point,
    /// World rotation $R$ as a unit quaternion.
    pub rotation: Rotation,
}

impl RigidKey {
    /// The identity pose at frame 0.
    pub fn identity() -> Self {
        Self {
            frame: 0.0,
            translation: [0.0; 3],
            rotation: Rotation::IDENTITY,
        }
    }
}

/// A rigid obstacle: geometry, a display mesh for viewers, and its keyframed pose.
#[derive(Clone)]
pub struct Obstacle {
    name: String,
    shape: SharedShape,
    display: TriMesh,
    keys: Vec<RigidKey>,
}

impl std::fmt::Debug for Obstacle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Obstacle")
            .field("name", &self.name)
            .field("keys", &self.keys)
            .finish()
    }
}

fn to_vec(p: Point) -> Vector {
    Vector::new(p[0], p[1], p[2])
}

fn to_point(v: Vector) -> Point {
    [v.x, v.y, v.z]
}

fn display_mesh((v, t): (Vec<Vector>, Vec<[u32; 3]>)) -> TriMesh {
    TriMesh::new(v.into_iter().map(to_point).collect(), t)
}

impl Obstacle {
    /// A primitive obstacle at the identity pose. `display_size` is the side of the square
    /// that shows a plane in viewers (planes are infinite; it does not affect collisions).
    pub fn primitive(
        name: &str,
        primitive: &Primitive,
        display_size: f64,
    ) -> Result<Self, ObstacleError> {
        let positive = |what: &'static str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(value)
            } else {
                Err(ObstacleError::Dimension {
                    name: name.to_string(),
                    what,
                    value,
                })
            }
        };
        let (shape, display) = match *primitive {
            Primitive::Sphere { radius } => {
                let b = Ball::new(positive("radius", radius)?);
                (SharedShape::new(b), display_mesh(b.to_trimesh(32, 16)))
            }
            Primitive::Box { size } => {
                let h = Vector::new(
                    positive("size[0]", size[0])? / 2.0,
                    positive("size[1]", size[1])? / 2.0,
                    positive("size[2]", size[2])? / 2.0,
                );
                let c = Cuboid::new(h);
                (SharedShape::new(c), display_mesh(c.to_trimesh()))
            }
            Primitive::Cylinder { radius, height } => {
                let c = Cylinder::new(
                    positive("height", height)? / 2.0,
                    positive("radius", radius)?,
                );
                (SharedShape::new(c), display_mesh(c.to_trimesh(48)))
            }
            Primitive::Capsule { radius, length } => {
                let c = Capsule::new_y(
                    positive("length", length)? / 2.0,
                    positive("radius", radius)?,
                );
                (SharedShape::new(c), display_mesh(c.to_trimesh(32, 8)))
            }
            Primitive::Plane { normal } => {
                let n = to_vec(normal);
                let len = positive("the normal's length", n.length())?;
                let n = n / len;
                let s = positive("the display size", display_size)? / 2.0;
                let (u, v) = n.any_orthonormal_pair();
                let corners = [-u - v, u - v, u + v, -u + v].map(|c| to_point(c * s));
                // Counter-clockwise around n, so the square faces out of the solid.
                let ccw = u.cross(v).dot(n) > 0.0;
                let tris = if ccw {
                    vec![[0, 1, 2], [0, 2, 3]]
                } else {
                    vec![[0, 2, 1], [0, 3, 2]]
                };
                (
                    SharedShape::halfspace(n),
                    TriMesh::new(corners.to_vec(), tris),
                )
            }
        };
        Ok(Self {
            name: name.to_string(),
            shape,
            display,
            keys: vec![RigidKey::identity()],
        })
    }

    /// A mesh obstacle at the identity pose; refused unless closed and consistently oriented
    /// (an inward-facing mesh is flipped).
    pub fn from_mesh(name: &str, mesh: &TriMesh) -> Result<Self, ObstacleError> {
        let topology = Topology::new(mesh.num_vertices(), &mesh.triangles);
        let open: Vec<usize> = (0..topology.edges().len())
            .filter(|&e| topology.edge_faces(e).len() != 2)
            .collect();
        if let Some(&e) = open.first() {
            return Err(ObstacleError::NotClosed {
                name: name.to_string(),
                open_edges: open.len(),
                example: topology.edges()[e],
            });
        }
        if !topology.is_consistently_oriented() {
            return Err(ObstacleError::NotOriented {
                name: name.to_string(),
            });
        }
        let mut triangles = mesh.triangles.clone();
        if crate::mesh::enclosed_volume(&mesh.positions, &mesh.triangles) < 0.0 {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        let display = TriMesh::new(mesh.positions.clone(), triangles);
        let vertices = display.positions.iter().map(|&p| to_vec(p)).collect();
        let trimesh =
            ParryMesh::with_flags(vertices, display.triangles.clone(), TriMeshFlags::ORIENTED)
                .map_err(|e| ObstacleError::Build {
                    name: name.to_string(),
                    cause: e.to_string(),
                })?;
        Ok(Self {
            name: name.to_string(),
            shape: SharedShape::new(trimesh),
            display,
            keys: vec![RigidKey::identity()],
        })
    }

    /// Replaces the motion by `keys` (at least one, strictly increasing frames).
    pub fn with_keys(mut self, keys: Vec<RigidKey>) -> Result<Self, ObstacleError> {
        for (index, k) in keys.iter().enumerate() {
            let finite = k.frame.is_finite()
                && k.translation.iter().all(|c| c.is_finite())
                && k.rotation.is_finite();
            if !finite {
                return Err(ObstacleError::NonFiniteKey {
                    name: self.name.clone(),
                    index,
                });
            }
        }
        let frames: Vec<f64> = keys.iter().map(|k| k.frame).collect();
        if let Some(index) = first_out_of_order(&frames) {
            return Err(ObstacleError::KeysOutOfOrder {
                name: self.name.clone(),
                index,
                frame: frames[index],
                previous: frames[index - 1],
            });
        }
        self.keys = if keys.is_empty() {
            vec![RigidKey::identity()]
        } else {
            keys.into_iter()
                .map(|k| RigidKey {
                    rotation: k.rotation.normalize(),
                    ..k
                })
                .collect()
        };
        Ok(self)
    }

    /// The obstacle's name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Its keys, in frame order.
    pub fn keys(&self) -> &[RigidKey] {
        &self.keys
    }
    /// The mesh that shows it, in its local frame (for viewers; planes are a finite square).
    pub fn display_mesh(&self) -> &TriMesh {
        &self.display
    }

    /// The interpolated world pose at `frame`: `(translation, rotation)`.
    pub fn pose_at(&self, frame: f64) -> (Point, Rotation) {
        let frames: Vec<f64> = self.keys.iter().map(|k| k.frame).collect();
        let (i, j, t) = bracket(&frames, frame);
        let (a, b) = (&self.keys[i], &self.keys[j]);
        (
            lerp(a.translation, b.translation, t),
            slerp(a.rotation, b.rotation, t),
        )
    }

    /// Its display mesh and its pose at each of `frames` frames (one key when it does not
    /// move), at `fps`, for [`crate::io::write_gltf_scene`].
    pub fn gltf_track(&self, frames: usize, fps: f64) -> crate::io::GltfRigidMesh {
        let n = if self.keys.len() > 1 {
            frames.max(1)
        } else {
            1
        };
        let keys = (0..n)
            .map(|k| {
                let (t, r) = self.pose_at(k as f64);
                (k as f64 / fps, t, [r.x, r.y, r.z, r.w])
            })
            .collect();
        crate::io::GltfRigidMesh {
            name: self.name.clone(),
            mesh: self.display.clone(),
            keys,
        }
    }

    /// The obstacle placed at `frame`, ready for point queries.
    pub fn placed(&self, frame: f64) -> Placed<'_> {
        let (t, r) = self.pose_at(frame);
        let pose = Pose::from_parts(to_vec(t), r);
        Placed {
            shape: &self.shape,
            aabb: self.shape.compute_aabb(&pose),
            pose,
        }
    }
}

/// An obstacle at one pose.
pub struct Placed<'a> {
    shape: &'a SharedShape,
    pose: Pose,
    aabb: Aabb,
}

impl Placed<'_> {
    /// When `p` is strictly inside: the closest surface point and the penetration depth.
    /// Points outside the obstacle's bounding box are rejected without a projection.
    pub fn penetration(&self, p: Point) -> Option<(Point, f64)> {
        let v = to_vec(p);
        let (lo, hi) = (self.aabb.mins, self.aabb.maxs);
        if v.x < lo.x || v.y < lo.y || v.z < lo.z || v.x > hi.x || v.y > hi.y || v.z > hi.z {
            return None;
        }
        let proj = self.shape.project_point(&self.pose, v, false);
        let depth = (proj.point - v).length();
        if depth > 0.0 && depth.is_finite() {
            return proj.is_inside.then(|| (to_point(proj.point), depth));
        }
        // A degenerate projection: the point is its own projection (on the surface, or where
        // every direction is closest, as at a ball's centre) or the projection is not finite.
        // Inside points then take the projection of a nearby point, offset by a billionth of
        // the box along +x, +y, +z in turn, so that a vertex at an obstacle's centre is still
        // found, deterministically. A point on the surface stays no hit: the surface it finds
        // is not farther than the offset.
        if !self.shape.contains_point(&self.pose, v) {
            return None;
        }
        let step = 1e-9 * (hi - lo).length().max(f64::MIN_POSITIVE);
        [Vector::X, Vector::Y, Vector::Z]
            .into_iter()
            .find_map(|axis| {
                let q = self
                    .shape
                    .project_point(&self.pose, v + axis * step, false)
                    .point;
                let depth = (q - v).length();
                (depth > 2.0 * step && depth.is_finite()).then(|| (to_point(q), depth))
            })
    }

    /// Distance from `p` to the obstacle's surface (whether inside or outside).
    pub fn surface_distance(&self, p: Point) -> f64 {
        let v = to_vec(p);
        (self.shape.project_point(&self.pose, v, false).point - v).length()
    }

    /// The world-space mesh of `display` at this pose.
    pub fn transform(&self, display: &TriMesh) -> TriMesh {
        let positions = display
            .positions
            .iter()
            .map(|&p| to_point(self.pose.transform_point(to_vec(p))))
            .collect();
        display.with_positions(positions)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn a_point_at_a_ball_centre_is_inside_and_a_surface_point_is_not() {
        let s = Obstacle::primitive("s", &Primitive::Sphere { radius: 0.5 }, 1.0)
            .unwrap()
            .with_keys(vec![RigidKey {
                frame: 0.0,
                translation: [1.0, 2.0, 3.0],
                rotation: Rotation::IDENTITY,
            }])
            .unwrap();
        let placed = s.placed(0.0);
        let (q, depth) = placed
            .penetration([1.0, 2.0, 3.0])
            .expect("the centre is inside");
        assert!((depth - 0.5).abs() < 1e-12, "depth {depth}");
        let r = ((q[0] - 1.0).powi(2) + (q[1] - 2.0).powi(2) + (q[2] - 3.0).powi(2)).sqrt();
        assert!((r - 0.5).abs() < 1e-12, "surface point at {r}");
        assert!(placed.penetration([1.5, 2.0, 3.0]).is_none());
        assert!(placed.penetration([1.0, 2.0, 3.6]).is_none());
    }

    #[test]
    fn primitives_report_inside_points_with_their_surface_point() {
        let s = Obstacle::primitive("s", &Primitive::Sphere { radius: 1.0 }, 1.0).unwrap();
        let s = s
            .with_keys(vec![RigidKey {
                frame: 0.0,
                translation: [2.0, 0.0, 0.0],
                rotation: Rotation::IDENTITY,
            }])
            .unwrap();
        let placed = s.placed(0.0);
        let (q, d) = placed.penetration([2.5, 0.0, 0.0]).unwrap();
        assert!((d - 0.5).abs() < 1e-12 && (q[0] - 3.0).abs() < 1e-12);
        assert!(placed.penetration([3.5, 0.0, 0.0]).is_none());
        assert!(placed.penetration([0.0, 0.0, 0.0]).is_none());

        let c = Obstacle::primitive(
            "c",
            &Primitive::Cylinder {
                radius: 0.5,
                height: 4.0,
            },
            1.0,
        )
        .unwrap();
        let (q, d) = c.placed(0.0).penetration([0.4, 1.0, 0.0]).unwrap();
        assert!((d - 0.1).abs() < 1e-12 && (q[0] - 0.5).abs() < 1e-12);

        let p = Obstacle::primitive(
            "p",
            &Primitive::Plane {
                normal: [0.0, 0.0, 2.0],
            },
            1.0,
        )
        .unwrap();
        let (q, d) = p.placed(0.0).penetration([1.0, 1.0, -0.25]).unwrap();
        assert!((d - 0.25).abs() < 1e-12 && q[2].abs() < 1e-12);
        assert!(Obstacle::primitive("b", &Primitive::Sphere { radius: -1.0 }, 1.0).is_err());
    }

    #[test]
    fn closed_meshes_in_either_orientation_work_and_open_ones_are_refused() {
        let tube = generate::tube(1.0, 2.0, 16, 4, true);
        let o = Obstacle::from_mesh("tube", &tube).unwrap();
        assert!(o.placed(0.0).penetration([1.0, 0.0, 0.5]).is_some());
        assert!(o.placed(0.0).penetration([1.0, 0.0, 1.5]).is_none());
        let mut flipped = tube.clone();
        for t in &mut flipped.triangles {
            t.swap(1, 2);
        }
        let o = Obstacle::from_mesh("flipped", &flipped).unwrap();
        assert!(o.placed(0.0).penetration([1.0, 0.0, 0.5]).is_some());
        assert!(o.placed(0.0).penetration([1.0, 0.0, 1.5]).is_none());
        let open = generate::tube(1.0, 2.0, 16, 4, false);
        let e = Obstacle::from_mesh("open", &open).unwrap_err();
        assert!(
            matches!(e, ObstacleError::NotClosed { open_edges: 32, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("not closed"), "{e}");
    }

    #[test]
    fn keyed_motion_interpolates_translation_and_rotation() {
        let o = Obstacle::primitive("s", &Primitive::Sphere { radius: 1.0 }, 1.0)
            .unwrap()
            .with_keys(vec![
                RigidKey::identity(),
                RigidKey {
                    frame: 4.0,
                    translation: [4.0, 0.0, 0.0],
                    rotation: Rotation::from_axis_angle(Vector::Z, 2.0),
                },
            ])
            .unwrap();
        let (t, r) = o.pose_at(1.0);
        assert!((t[0] - 1.0).abs() < 1e-12);
        assert!((r.to_axis_angle().1 - 0.5).abs() < 1e-12);
        let bad = o
            .clone()
            .with_keys(vec![RigidKey::identity(), RigidKey::identity()]);
        assert!(matches!(
            bad,
            Err(ObstacleError::KeysOutOfOrder { index: 1, .. })
        ));
    }
}
