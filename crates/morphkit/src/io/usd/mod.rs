//! USD text layers (`.usda`, Pixar's Universal Scene Description) for pipelines: baked
//! animation as a `Mesh` with time-sampled `points`, and blendshape rigs as `UsdSkel`
//! `BlendShape` targets.
//!
//! Layout of [`write_usd_animation`] (USD `UsdGeomMesh`, `UsdGeomPointBased`, stage metadata of
//! `UsdGeom` "Stage Up Axis" and "Linear Units"):
//!
//! ```text
//! #usda 1.0
//! ( defaultPrim = "NAME"  startTimeCode = 0  endTimeCode = #frames − 1
//!   timeCodesPerSecond = fps  framesPerSecond = fps  upAxis = "Y"  metersPerUnit = 1
//!   customLayerData = { string morphkit = "<provenance JSON>" } )
//! def Xform "NAME" (kind = "component") {
//!     def Mesh "mesh" {
//!         int[] faceVertexCounts, int[] faceVertexIndices   (the original polygons when kept)
//!         point3f[] points (frame 0) and points.timeSamples = { 0: […], 1: […], … }
//!         float3[] extent (frame 0) and extent.timeSamples (per frame bounds)
//!         uniform bool doubleSided (open meshes)   uniform token subdivisionScheme = "none"
//! } }
//! ```
//!
//! Frame `k` is time code `k`. Floats are written with the shortest decimal that reads back to
//! the same `f32` (USD stores `point3f`), so the same input gives the same bytes. Counter-
//! clockwise triangles are USD's default `rightHanded` orientation.
//!
//! [`write_usd_blendshapes`] writes a `SkelRoot` holding the base `Mesh` (with the
//! `SkelBindingAPI`, `skel:blendShapes` and `skel:blendShapeTargets`), one `BlendShape` child per
//! target with its `offsets` and `pointIndices` (only the points that move), and a `Skeleton`
//! without joints whose `SkelAnimation` names the blend shapes and holds their weights (USD
//! `UsdSkel` "Blend Shapes"). [`read_usd_animation`] is a minimal reader for the files
//! [`write_usd_animation`] writes (the mesh's faces and its `points` samples).

mod read;
mod text;
mod write;

pub use read::{parse_usd_animation, read_usd_animation, UsdAnimation};
pub use write::{
    write_usd_animation, write_usd_blendshape_rig, write_usd_blendshapes, UsdBlendShape,
};

/// The stage's up axis (`upAxis` layer metadata).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum UpAxis {
    /// `+Y` up, as in glTF and morphkit's generated meshes (default).
    #[default]
    Y,
    /// `+Z` up.
    Z,
}

/// How the USD writers write a layer.
#[derive(Clone, Debug, PartialEq)]
pub struct UsdOptions {
    /// Name of the root prim (made a valid USD identifier). Default `morphkit`.
    pub name: String,
    /// `upAxis`. Default [`UpAxis::Y`].
    pub up_axis: UpAxis,
    /// `metersPerUnit`: the length of one coordinate unit in metres. Default 1.
    pub meters_per_unit: f64,
    /// JSON stored as the string `morphkit` of the layer's `customLayerData` (the command, the
    /// sources, the weights per frame). Default `None`.
    pub custom_data: Option<serde_json::Value>,
}

impl Default for UsdOptions {
    fn default() -> Self {
        Self {
            name: "morphkit".into(),
            up_axis: UpAxis::Y,
            meters_per_unit: 1.0,
            custom_data: None,
        }
    }
}
