//! The correspondence arguments that `morphkit transfer` and `morphkit rig` share: markers
//! (the correspondence is computed first) or a correspondence file, how matched gradients
//! combine, and the closest-point refinement (on by default; `--no-refine`). Every default is
//! the library's (issue 55): `--combine` is [`GradientCombine::default`], and the
//! correspondence is computed with [`CorrespondenceArgs::defaults`] changed only by the flags
//! given.

use super::correspond::{confidence_summary, print_summary, summary};
use anyhow::{bail, Context};
use morphkit::transfer::{
    correspond, Correspondence, CorrespondenceOptions, GradientCombine, Markers,
};
use morphkit::TriMesh;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Where the correspondence comes from, and how it is used.
#[derive(clap::Args, Clone, Debug)]
pub struct CorrespondenceArgs {
    /// Marker pairs (computes the correspondence first).
    #[arg(long, value_name = "JSON", conflicts_with = "correspondence")]
    pub markers: Option<PathBuf>,
    /// A correspondence written by `morphkit correspond`.
    #[arg(long, value_name = "JSON")]
    pub correspondence: Option<PathBuf>,
    /// How gradients of several matched source triangles combine: inverse-distance (weights
    /// 1/d; exact on a mesh onto itself), mean, or nearest.
    #[arg(long, default_value = GradientCombine::default().name(),
        value_parser = GradientCombine::NAMES)]
    pub combine: String,
    /// With --markers: refine the correspondence by closest points (Sumner & Popović 2004,
    /// Sec. 5) before matching. The default of `transfer` (issue 40), not of `rig`.
    #[arg(long, conflicts_with = "no_refine")]
    pub refine: bool,
    /// With --markers: match the two least-squares warps directly, without the closest-point
    /// refinement (the default of `rig`, and of `transfer` before issue 40).
    #[arg(long)]
    pub no_refine: bool,
    /// The options a correspondence is computed with when no flag changes them: the
    /// library's [`CorrespondenceOptions::default`] (`transfer`), or a command's own (`rig`:
    /// [`morphkit::transfer::RigOptions::correspondence`]).
    #[arg(skip = CorrespondenceOptions::default())]
    pub defaults: CorrespondenceOptions,
}

/// `--refine` / `--no-refine` applied to `o` ([`CorrespondenceOptions::set_refine`]); neither
/// keeps `o`'s refinement.
pub fn apply_refine_flags(o: &mut CorrespondenceOptions, refine: bool, no_refine: bool) {
    if refine || no_refine {
        o.set_refine(refine);
    }
}

/// A correspondence obtained from [`CorrespondenceArgs`].
pub struct Obtained {
    pub correspondence: Correspondence,
    /// With --markers: the markers and options it was computed with (for a way back).
    pub computed_from: Option<(Markers, CorrespondenceOptions)>,
}

impl CorrespondenceArgs {
    /// Refuses a command line with neither source of a correspondence.
    pub fn require(&self) -> anyhow::Result<()> {
        if self.markers.is_none() && self.correspondence.is_none() {
            bail!(
                "give --markers JSON (marker pairs; the correspondence is computed first) or \
                 --correspondence JSON (a file written by morphkit correspond)"
            );
        }
        Ok(())
    }

    /// The input files these arguments name (none is ever written).
    pub fn inputs(&self) -> impl Iterator<Item = PathBuf> + '_ {
        self.markers.iter().chain(&self.correspondence).cloned()
    }

    /// The options a correspondence is computed with: [`CorrespondenceArgs::defaults`] with
    /// `--refine` / `--no-refine` applied ([`apply_refine_flags`]).
    pub fn correspondence_options(&self) -> CorrespondenceOptions {
        let mut o = self.defaults.clone();
        apply_refine_flags(&mut o, self.refine, self.no_refine);
        o
    }

    /// `--combine` as the library's option (clap admits only [`GradientCombine::NAMES`]).
    pub fn combine(&self) -> GradientCombine {
        GradientCombine::from_name(&self.combine).unwrap_or_default()
    }

    /// Computes the correspondence from `source` to `target` (with --markers) or reads it, and
    /// records how in `report["correspondence"]`; with `confidence`, a computed one's match
    /// confidence too (meaningful where source and target are placed alike: `rig` aligns
    /// the source to the target only later, so it asks for none).
    pub fn obtain(
        &self,
        source: &TriMesh,
        target: &TriMesh,
        report: &mut serde_json::Value,
        confidence: bool,
    ) -> anyhow::Result<Obtained> {
        self.require()?;
        if let Some(m) = &self.markers {
            let markers = Markers::read(m)?;
            crate::util::announce_work("computing the correspondence", target.num_vertices());
            let t0 = Instant::now();
            let copts = self.correspondence_options();
            let r = correspond(source, target, &markers, &copts).context("correspondence")?;
            let secs = t0.elapsed().as_secs_f64();
            print_summary(&r, secs);
            report["correspondence"] = summary(&r, secs);
            if confidence {
                let (_, conf) = confidence_summary(
                    source,
                    target,
                    &r.correspondence,
                    self.combine(),
                    "; `morphkit correspond --confidence FILE.ply` shows where",
                )?;
                report["correspondence"]["match_confidence"] = conf;
            }
            return Ok(Obtained {
                correspondence: r.correspondence,
                computed_from: Some((markers, copts)),
            });
        }
        let c = self.correspondence.as_ref().expect("checked by require");
        let text = std::fs::read_to_string(c)
            .with_context(|| format!("{}: cannot read the correspondence", c.display()))?;
        let corr = Correspondence::from_json(&text).with_context(|| format!("{}", c.display()))?;
        report["correspondence"] = json!({ "file": c, "seconds": 0.0 });
        Ok(Obtained {
            correspondence: corr,
            computed_from: None,
        })
    }
}
