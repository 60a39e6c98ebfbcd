//! Synthesis recipes: TOML, read with serde (`deny_unknown_fields`), paths relative to the
//! recipe file. Every error names the recipe file, line and key.
//!
//! ```toml
//! target = "camel-reference.obj.gz"
//! frames = 48                       # output frames
//! gamma = 0.1                       # optional: flexibility threshold (Sec. 3.2.1)
//! kappa = 10000.0                   # optional: Eq. 5 soft-constraint weight
//! fps = 24.0                        # optional: frame rate of a glTF output
//! rest = "camel-rest.obj"           # optional: a target pose under every layer
//! translation = "follow"            # or "fixed" (the paper's fixed constraint vertex)
//! follow_layer = 0                  # optional: whose motion the translation follows
//!
//! [[layer]]
//! name = "legs"                                # optional, for reports
//! source_reference = "horse-reference.obj.gz"  # omitted: the target itself (identity)
//! source_frames = "horse-gallop-*.obj.gz"      # a glob, a list, a directory, a .glb or a .pc2
//! source_scale = 0.5963                        # optional: multiplies the source frames
//! markers = "markers-horse-camel.json"         # or correspondence = "corr.json"
//! scribble = "legs.json"                       # {"triangles": [...]} or {"vertices": [...]}
//! mode = "blend"                               # or "compound"
//! offset = 0                                   # first output frame this layer drives
//! speed = 1.0                                  # source frames per output frame
//! loop = true                                  # wrap the source time
//! blend_region = "partitions"                  # or "geodesic" (Sec. 4) with blend_width
//! blend_width = 0.05                           # geodesic band, fraction of the target's diagonal
//!
//! [[pose]]                                     # Sec. 3.2.4, applied before synthesis
//! scribble = "neck.json"
//! axis = [0.0, 0.0, 1.0]
//! angle = 20.0                                 # degrees
//! layer = 1                                    # whose partitions refine the scribble (default 0)
//! ```

use super::BlendMode;
use serde::Deserialize;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// How the translation of output frames is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TranslationKind {
    /// The target's anchors follow the follow layer's source anchors. Default.
    #[default]
    Follow,
    /// The constraint vertex stays fixed.
    Fixed,
}

/// How a layer's weights are found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RegionKind {
    /// Intelligent scribbling and Eq. 5. Default.
    #[default]
    Partitions,
    /// A geodesic band around the scribble's boundary.
    Geodesic,
}

/// One path or several.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum PathList {
    /// A glob, a directory, an animation file or one mesh.
    One(String),
    /// Mesh files (each may be a glob).
    Many(Vec<String>),
}

/// A `[[layer]]` table.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerRecipe {
    /// Name for reports.
    pub name: Option<String>,
    /// Source reference mesh; omitted: the target (identity correspondence).
    pub source_reference: Option<Spanned<String>>,
    /// Source frames.
    pub source_frames: Spanned<PathList>,
    /// Multiplies the source frames (not the reference) about the origin. Default 1.
    pub source_scale: Option<Spanned<f64>>,
    /// Marker pairs (the correspondence is computed).
    pub markers: Option<Spanned<String>>,
    /// A correspondence written by `morphkit correspond`.
    pub correspondence: Option<Spanned<String>>,
    /// The scribble file.
    pub scribble: Spanned<String>,
    /// Blend or compound. Default blend.
    pub mode: Option<Spanned<BlendMode>>,
    /// First output frame driven. Default 0.
    pub offset: Option<usize>,
    /// Source frames per output frame. Default 1.
    pub speed: Option<Spanned<f64>>,
    /// Wrap the source time. Default false.
    #[serde(rename = "loop")]
    pub looped: Option<bool>,
    /// Partitions or geodesic. Default partitions.
    pub blend_region: Option<RegionKind>,
    /// Geodesic band width as a fraction of the target's bounding-box diagonal. Default 0.05.
    pub blend_width: Option<Spanned<f64>>,
}

/// A `[[pose]]` table.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseRecipe {
    /// The scribble of the part to turn.
    pub scribble: Spanned<String>,
    /// Rotation axis.
    pub axis: Spanned<[f64; 3]>,
    /// Angle in degrees.
    pub angle: f64,
    /// Layer whose partitions refine the scribble. Default 0.
    pub layer: Option<Spanned<usize>>,
}

/// A whole recipe.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Recipe {
    /// Target reference mesh.
    pub target: Spanned<String>,
    /// Output frame count.
    pub frames: Spanned<usize>,
    /// Flexibility threshold γ. Default 0.1.
    pub gamma: Option<Spanned<f64>>,
    /// Eq. 5 κ. Default 10 000.
    pub kappa: Option<Spanned<f64>>,
    /// Frame rate of a glTF output. Default 24.
    pub fps: Option<f64>,
    /// A rest pose of the target.
    pub rest: Option<Spanned<String>>,
    /// Translation convention. Default follow.
    pub translation: Option<TranslationKind>,
    /// Layer the translation follows.
    pub follow_layer: Option<Spanned<usize>>,
    /// The layers, bottom to top.
    #[serde(default, rename = "layer")]
    pub layers: Vec<Spanned<LayerRecipe>>,
    /// Pose edits.
    #[serde(default, rename = "pose")]
    pub poses: Vec<Spanned<PoseRecipe>>,
}

/// An error in a recipe: file, line, key and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}:{line}: {key}: {message}", path.display())]
pub struct RecipeError {
    /// The recipe file.
    pub path: PathBuf,
    /// 1-based line.
    pub line: usize,
    /// The key (or table) at fault.
    pub key: String,
    /// What is wrong, one line.
    pub message: String,
}

/// A parsed recipe with its text, for naming lines.
#[derive(Clone, Debug)]
pub struct RecipeFile {
    /// Where it was read from (paths in it are relative to its directory).
    pub path: PathBuf,
    /// Its text.
    pub text: String,
    /// The parsed recipe.
    pub recipe: Recipe,
}

impl RecipeFile {
    /// Parses `text` as the recipe at `path` (not read: `path` names it and anchors paths).
    pub fn parse(path: &Path, text: &str) -> Result<Self, RecipeError> {
        let recipe: Recipe = toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(1, |s| line_of(text, s.start));
            let message = e.message().replace('\n', " ");
            // The key: a missing field's name, else the key written on the failing line.
            let key = match e.message().split_once("missing field `") {
                Some((_, rest)) => rest.split('`').next().unwrap_or("recipe").to_string(),
                None => text
                    .lines()
                    .nth(line - 1)
                    .and_then(|l| l.split_once('='))
                    .map_or_else(|| "recipe".to_string(), |(k, _)| k.trim().to_string()),
            };
            RecipeError {
                path: path.to_path_buf(),
                line,
                key,
                message,
            }
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            text: text.to_string(),
            recipe,
        })
    }

    /// Reads and parses a recipe file.
    pub fn read(path: &Path) -> Result<Self, RecipeError> {
        let text = std::fs::read_to_string(path).map_err(|e| RecipeError {
            path: path.to_path_buf(),
            line: 0,
            key: "recipe".into(),
            message: format!("cannot read: {e}"),
        })?;
        Self::parse(path, &text)
    }

    /// 1-based line of a byte span's start.
    pub fn line(&self, span: Range<usize>) -> usize {
        line_of(&self.text, span.start)
    }

    /// An error at `span` about `key`.
    pub fn error(&self, span: Range<usize>, key: &str, message: impl ToString) -> RecipeError {
        RecipeError {
            path: self.path.clone(),
            line: self.line(span),
            key: key.to_string(),
            message: message.to_string().replace('\n', " "),
        }
    }

    /// A path of the recipe, resolved against its directory.
    pub fn resolve(&self, p: &str) -> PathBuf {
        let p = Path::new(p);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.path
                .parent()
                .map_or_else(|| p.to_path_buf(), |d| d.join(p))
        }
    }
}

fn line_of(text: &str, offset: usize) -> usize {
    1 + text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"target = "camel.obj"
frames = 48
gamma = 0.1

[[layer]]
source_reference = "horse.obj"
source_frames = "gallop-*.obj"
markers = "m.json"
scribble = "legs.json"
mode = "blend"
offset = 0
speed = 1.0
loop = true

[[layer]]
source_frames = ["a.obj", "b.obj"]
scribble = "head.json"
mode = "compound"
blend_region = "geodesic"
blend_width = 0.1

[[pose]]
scribble = "neck.json"
axis = [0.0, 0.0, 1.0]
angle = 20.0
"#;

    #[test]
    fn parses_and_resolves() {
        let r = RecipeFile::parse(Path::new("/data/r/recipe.toml"), GOOD).unwrap();
        assert_eq!(r.recipe.layers.len(), 2);
        assert_eq!(r.recipe.poses.len(), 1);
        let l = r.recipe.layers[1].get_ref();
        assert_eq!(l.mode.as_ref().unwrap().get_ref(), &BlendMode::Compound);
        assert_eq!(l.blend_region, Some(RegionKind::Geodesic));
        assert_eq!(r.line(l.scribble.span()), 17);
        assert_eq!(r.line(r.recipe.layers[1].span()), 15);
        assert_eq!(r.resolve("m.json"), PathBuf::from("/data/r/m.json"));
        assert_eq!(r.resolve("/abs.obj"), PathBuf::from("/abs.obj"));
    }

    #[test]
    fn misspelt_keys_and_bad_values_name_the_line() {
        let bad = GOOD.replace("speed = 1.0", "sped = 1.0");
        let e = RecipeFile::parse(Path::new("r.toml"), &bad).unwrap_err();
        assert_eq!(e.line, 12, "{e}");
        assert_eq!(e.key, "sped");
        assert!(
            e.to_string().starts_with("r.toml:12: sped: unknown field"),
            "{e}"
        );
        let bad = GOOD.replace("mode = \"compound\"", "mode = \"mix\"");
        let e = RecipeFile::parse(Path::new("r.toml"), &bad).unwrap_err();
        assert_eq!(e.line, 18, "{e}");
        let bad = GOOD.replace("frames = 48\n", "");
        let e = RecipeFile::parse(Path::new("r.toml"), &bad).unwrap_err();
        assert!(e.message.contains("frames"), "{e}");
    }
}
