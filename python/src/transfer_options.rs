//! The keyword options of `Correspondence.from_markers`, `Transfer` and `RigTransfer`, and
//! `morphkit.transfer_defaults()`. Every default is the library's (issue 55: one answer per
//! entry point): a keyword left at `None` takes [`CorrespondenceOptions::default`],
//! [`TransferOptions::default`] or [`RigOptions::default`], which `morphkit transfer`,
//! `correspond`, `rig` and `synth` use too, so nothing here restates a default.

use crate::dict::to_dict;
use crate::errors::{new_err, Kind};
use morphkit::transfer::rig::RigOptions;
use morphkit::transfer::{
    CorrespondenceOptions, GradientCombine, GradientFrame, TransferOptions, TranslationMode,
    TriangleWeighting,
};
use pyo3::prelude::*;

/// `combine=`: one of [`GradientCombine::NAMES`]; `None` the library's default.
pub fn combine_of(name: Option<&str>) -> PyResult<GradientCombine> {
    let Some(name) = name else {
        return Ok(GradientCombine::default());
    };
    GradientCombine::from_name(name).ok_or_else(|| {
        new_err(
            Kind::Transfer,
            format!(
                "combine: expected one of {:?}, got {name:?}",
                GradientCombine::NAMES
            ),
        )
    })
}

/// `refine=` on the library's correspondence defaults (`None` keeps them).
pub fn correspondence_options(refine: Option<bool>) -> CorrespondenceOptions {
    let mut o = CorrespondenceOptions::default();
    if let Some(r) = refine {
        o.set_refine(r);
    }
    o
}

/// The keyword arguments of `Transfer` on the library's [`TransferOptions::default`]: each
/// `None` keeps the default.
pub struct TransferKeywords<'a> {
    pub combine: Option<&'a str>,
    pub translation: Option<&'a str>,
    pub local_stretch: Option<bool>,
    pub area_weighted: Option<bool>,
    pub fold_guard: Option<bool>,
}

impl TransferKeywords<'_> {
    /// The options these keywords ask for.
    pub fn options(&self) -> PyResult<TransferOptions> {
        let mut o = TransferOptions {
            combine: combine_of(self.combine)?,
            ..TransferOptions::default()
        };
        if let Some(t) = self.translation {
            o.translation = TranslationMode::from_name(t).ok_or_else(|| {
                new_err(
                    Kind::Transfer,
                    format!(
                        "translation: expected one of {:?}, got {t:?}",
                        TranslationMode::NAMES
                    ),
                )
            })?;
        }
        if let Some(l) = self.local_stretch {
            o.frame = if l {
                GradientFrame::LocalStretch
            } else {
                GradientFrame::World
            };
        }
        if let Some(a) = self.area_weighted {
            o.solver.weighting = if a {
                TriangleWeighting::Area
            } else {
                TriangleWeighting::Uniform
            };
        }
        match self.fold_guard {
            Some(false) if o.frame == GradientFrame::World => {
                return Err(new_err(
                    Kind::Transfer,
                    "fold_guard=False: the fold guard belongs to the local-stretch frame \
                     (local_stretch=False has none to turn off)",
                ))
            }
            Some(false) => o.fold_guard = None,
            Some(true) if o.fold_guard.is_none() => o.fold_guard = Some(Default::default()),
            _ => {}
        }
        Ok(o)
    }
}

/// `opts` as the keyword values that ask for it (`Transfer.options`).
pub fn transfer_dict<'py>(py: Python<'py>, opts: &TransferOptions) -> PyResult<Bound<'py, PyAny>> {
    to_dict(py, &transfer_json(opts))
}

fn transfer_json(opts: &TransferOptions) -> serde_json::Value {
    serde_json::json!({
        "combine": opts.combine.name(),
        "translation": opts.translation.name(),
        "local_stretch": opts.frame == GradientFrame::LocalStretch,
        "area_weighted": opts.solver.weighting == TriangleWeighting::Area,
        "fold_guard": opts.fold_guard.is_some(),
    })
}

/// The library's defaults as the keyword values of `Correspondence.from_markers` (`refine`)
/// and `Transfer` (`combine`, `translation`, `local_stretch`, `area_weighted`,
/// `fold_guard`): what a keyword left out (or `None`) means, and what `morphkit transfer`
/// does without flags.
///
/// >>> morphkit.transfer_defaults()["local_stretch"]
/// True
#[pyfunction]
pub fn transfer_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let mut v = transfer_json(&TransferOptions::default());
    v["refine"] = CorrespondenceOptions::default().refine.is_some().into();
    to_dict(py, &v)
}

/// The library's defaults of a rig transfer (`morphkit rig`), as keyword values: `refine`, the
/// closest-point refinement of the rig's correspondence from markers
/// ([`RigOptions::correspondence`]: off, unlike `transfer`'s), and the [`RigOptions::default`]
/// transfer options `RigTransfer` uses (`combine`, `local_stretch`, `area_weighted`,
/// `fold_guard`; a rig has no root motion, so no `translation`). A client that computes a rig's
/// correspondence (the Blender add-on) takes `refine` from here, so that it moves the rig
/// as `morphkit rig` does.
///
/// >>> morphkit.rig_defaults()["refine"]
/// False
#[pyfunction]
pub fn rig_defaults(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let mut v = transfer_json(&RigOptions::default().transfer);
    if let Some(o) = v.as_object_mut() {
        o.remove("translation");
    }
    v["refine"] = RigOptions::correspondence().refine.is_some().into();
    to_dict(py, &v)
}
