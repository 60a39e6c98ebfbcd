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
//!
//! Foundations: [`mesh`] (connectivity, topology, shape sets), [`io`] (OBJ, PLY, OFF, glTF/GLB,
//! PC2), [`sparse`] (faer sparse Cholesky with symbolic reuse) and [`geom`] (small dense math).
#![warn(missing_docs)]

pub mod geom;
pub mod io;
pub mod mesh;
pub mod sparse;
pub mod springs;
pub mod transfer;

pub use mesh::{ShapeSet, TriMesh};
