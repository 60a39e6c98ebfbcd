//! The TOML schema of a scene file (see [`super::scene`] for its meaning). Every table
//! refuses unknown keys; values that need a line in their error messages keep their span.

use serde::Deserialize;
use toml::Spanned;

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneFile {
    pub base: Spanned<String>,
    pub targets: Spanned<Vec<Spanned<String>>>,
    pub weights: Spanned<WeightsSpec>,
    #[serde(default)]
    pub blend: BlendSpec,
    #[serde(default)]
    pub collision: CollisionSpec,
    #[serde(default)]
    pub output: OutputSpec,
    #[serde(default, rename = "obstacle")]
    pub obstacles: Vec<Spanned<ObstacleSpec>>,
    #[serde(default, rename = "pull")]
    pub pulls: Vec<Spanned<PullSpec>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct WeightsSpec {
    pub frames: Option<Spanned<usize>>,
    pub alpha: Option<Spanned<[f64; 2]>>,
    pub constant: Option<Spanned<Vec<f64>>>,
    pub file: Option<Spanned<String>>,
    #[serde(default)]
    pub convex: bool,
}

#[derive(Deserialize, Debug)]
#[serde(untagged)]
pub(crate) enum FixedSpec {
    Mode(String),
    Ids(Vec<u32>),
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct BlendSpec {
    pub fixed: Option<Spanned<FixedSpec>>,
    pub k0: Option<f64>,
    pub bending: Option<bool>,
    pub hinge_weight: Option<f64>,
    pub tether: Option<f64>,
    pub kinematic_stretch: Option<f64>,
    pub thin_band_rings: Option<usize>,
    pub tolerance: Option<f64>,
    pub max_newton_iterations: Option<usize>,
    pub interior: Option<Spanned<String>>,
    pub anchor: Option<Spanned<String>>,
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct CollisionSpec {
    pub tolerance: Option<f64>,
    pub max_rounds: Option<usize>,
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct OutputSpec {
    pub fps: Option<f64>,
}

#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub(crate) struct RotationSpec {
    pub axis: [f64; 3],
    pub degrees: f64,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct RigidKeySpec {
    pub frame: Spanned<f64>,
    #[serde(default)]
    pub translation: [f64; 3],
    pub rotation: Option<RotationSpec>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct ObstacleSpec {
    pub name: Option<String>,
    pub mesh: Option<Spanned<String>>,
    pub shape: Option<Spanned<String>>,
    pub radius: Option<f64>,
    pub size: Option<[f64; 3]>,
    pub height: Option<f64>,
    pub length: Option<f64>,
    pub normal: Option<[f64; 3]>,
    pub translation: Option<[f64; 3]>,
    pub rotation: Option<RotationSpec>,
    #[serde(default)]
    pub key: Vec<RigidKeySpec>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct PullKeySpec {
    pub frame: Spanned<f64>,
    pub position: [f64; 3],
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
pub(crate) struct PullSpec {
    pub vertex: Spanned<u32>,
    pub stiffness: Option<Spanned<f64>>,
    pub position: Option<[f64; 3]>,
    #[serde(default)]
    pub key: Vec<PullKeySpec>,
}
