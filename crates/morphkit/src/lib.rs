//! # morphkit
//!
//! Physically plausible, reusable mesh animation:
//!
//! - **Physical blendshapes** (Ma et al. 2012): each blendshape target is a mass–spring system;
//!   blending interpolates the springs' rest lengths and the blended shape is the system's
//!   equilibrium, which removes the shrinking of linear blendshapes under large rotations.
//!   See [`springs`].
//! - **Example-driven animation transfer** (Wang & Lee 2008, building on Sumner & Popović 2004):
//!   marker correspondence by least-squares meshes and deformation-gradient transfer onto a
//!   different mesh. See [`transfer`].
//! - **Animation synthesis** (Wang & Lee 2008): parts of several animations assembled on one
//!   target by scribbles, blend weights and rotation-aware gradient blending. See [`synth`].
//!
//! Set-up once, then many cheap solves (here a slider from straight to bent):
//!
//! ```
//! use morphkit::mesh::{generate, ShapeSet};
//! use morphkit::springs::{BlendOptions, PhysicalBlend, Weights};
//!
//! let bar = generate::bar(4.0, 0.6, 2, 16);
//! let bent = generate::bend(&bar.positions, 2.0, 2.0, 2.0);
//! let shapes = ShapeSet::new(
//!     bar.clone(),
//!     vec![("straight".into(), bar.positions.clone()), ("bent".into(), bent)],
//! )?;
//! let mut solver = PhysicalBlend::new(&shapes, &BlendOptions::default())?;
//! for k in 0..=10 {
//!     let result = solver.solve(&Weights::Alpha(k as f64 / 10.0))?;
//!     assert!(result.stats.converged);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Foundations: [`mesh`] (connectivity, topology, shape sets), [`io`] (OBJ, PLY, OFF, glTF/GLB,
//! PC2), [`sparse`] (faer sparse Cholesky with symbolic reuse) and [`geom`] (small dense math).
#![warn(missing_docs)]

pub mod bake;
pub mod clip;
pub mod geom;
pub mod io;
pub mod mesh;
pub mod scene;
pub mod sparse;
pub mod springs;
pub mod synth;
pub mod transfer;

pub use mesh::{ShapeSet, TriMesh};
