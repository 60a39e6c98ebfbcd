//! The memory a read decodes, counted over the whole file before anything is decoded
//! (issue 55).
//!
//! A glTF file may use one accessor many times (every primitive of a mesh naming the same
//! `POSITION`, thousands of morph targets naming one displacement accessor) and may give an
//! accessor without a buffer view, all zeros, any count: a file of a kilobyte can make a
//! reader decode gigabytes. Limits per accessor or per view do not see the reuse, so the read
//! adds up the decoded bytes of **every use** of every accessor and view it is about to decode
//! and refuses the file, naming the estimate and the budget, when they exceed
//! [`MAX_DECODED_BYTES`]:
//!
//! - each meshopt-compressed buffer view: its decoded `byteLength` (every one is decoded once);
//! - each primitive of the chosen mesh: its `POSITION`, `NORMAL` and index accessors and each
//!   morph target's `POSITION` (a target without one costs the primitive's vertices);
//! - each animation sampler driving the chosen mesh's weights: input and output, twice (the
//!   values and the keys made from them);
//! - for a rig morphkit split over several meshes: every part's morph targets (their values
//!   and the absolute positions made from them) and every part's keys over the whole rig.
//!
//! A use costs 8 bytes per component (values are decoded to `f64`) plus, for a sparse
//! accessor, 8 bytes per sparse index and value. What the read keeps is about this sum; the
//! intermediate copies of one accessor come and go.

use super::accessor::components;
use super::anim::weight_channels;
use crate::io::IoError;
use ::gltf::{Accessor, Semantic};
use std::path::Path;

/// The most bytes one glTF file may decode, over all uses of its accessors and views: 4 GiB.
/// A rig reaches it at about 1 800 morph targets of a 100 000-vertex mesh (24 bytes per vertex
/// and target), whose positions as `f32` would already be a 2.1 GB file; the solver's own
/// default limit (`--max-memory`) is 8 GiB.
pub(crate) const MAX_DECODED_BYTES: u64 = 4 << 30;

/// The running total.
#[derive(Default)]
struct Tally {
    bytes: u64,
    uses: u64,
}

impl Tally {
    fn add(&mut self, bytes: u64) {
        self.bytes = self.bytes.saturating_add(bytes);
        self.uses += 1;
    }
    fn accessor(&mut self, acc: &Accessor) {
        self.add(decoded_bytes(acc));
    }
}

/// The bytes one use of `acc` decodes: 8 per component, and 8 per sparse index and value.
fn decoded_bytes(acc: &Accessor) -> u64 {
    let comps = components(acc.dimensions()) as u64;
    let dense = (acc.count() as u64).saturating_mul(comps);
    let sparse = acc
        .sparse()
        .map_or(0, |s| (s.count() as u64).saturating_mul(comps + 1));
    dense.saturating_add(sparse).saturating_mul(8)
}

/// Bytes as GiB with two decimals, for messages.
fn gib(b: u64) -> String {
    format!("{:.2} GiB", b as f64 / (1u64 << 30) as f64)
}

/// Fails, before any accessor or view is decoded, when reading `mesh` of `doc` would decode
/// more than [`MAX_DECODED_BYTES`] (see the [module documentation](self)).
pub(super) fn check(
    path: &Path,
    doc: &::gltf::Document,
    mesh: &::gltf::Mesh,
) -> Result<(), IoError> {
    check_with(path, doc, mesh, MAX_DECODED_BYTES)
}

fn check_with(
    path: &Path,
    doc: &::gltf::Document,
    mesh: &::gltf::Mesh,
    budget: u64,
) -> Result<(), IoError> {
    let mut t = Tally::default();
    let mut views = 0u64;
    for view in doc.views() {
        if super::extensions::is_compressed(&view) {
            t.add(view.length() as u64);
            views += 1;
        }
    }
    let mut vertices = 0u64;
    for prim in mesh.primitives() {
        let n = prim
            .get(&Semantic::Positions)
            .map_or(0, |a| a.count() as u64);
        vertices = vertices.saturating_add(n);
        for sem in [Semantic::Positions, Semantic::Normals] {
            if let Some(a) = prim.get(&sem) {
                t.accessor(&a);
            }
        }
        if let Some(a) = prim.indices() {
            t.accessor(&a);
        }
        for target in prim.morph_targets() {
            match target.positions() {
                Some(a) => t.accessor(&a),
                None => t.add(n.saturating_mul(24)),
            }
        }
    }
    let targets = |m: &::gltf::Mesh| {
        m.primitives()
            .next()
            .map_or(0, |p| p.morph_targets().count() as u64)
    };
    // The samplers driving a mesh's weights (each counted once, however many channels use it)
    // and their key counts.
    let samplers = |m: &::gltf::Mesh| {
        let mut seen: Vec<(usize, usize)> = Vec::new();
        let mut out = Vec::new();
        for ch in weight_channels(doc, m.index()) {
            if seen.contains(&(ch.anim, ch.sampler)) {
                continue;
            }
            seen.push((ch.anim, ch.sampler));
            if let Some(s) = doc
                .animations()
                .nth(ch.anim)
                .and_then(|a| a.samplers().nth(ch.sampler))
            {
                out.push((s.input(), s.output()));
            }
        }
        out
    };
    if targets(mesh) > 0 {
        for (input, output) in samplers(mesh) {
            let b = decoded_bytes(&input).saturating_add(decoded_bytes(&output));
            t.add(b.saturating_mul(2));
        }
    }
    if mesh.index() == 0 {
        // A split rig: read_chunks decodes every part's targets and merges its keys into rows
        // over all of the rig's targets.
        let parts: Vec<_> = doc
            .meshes()
            .filter(|m| super::read_chunks::rig_indices(m.extras()).is_some())
            .collect();
        if parts.first().is_some_and(|m| m.index() == 0) {
            let rig: u64 = parts.iter().map(targets).sum();
            for part in &parts {
                if let Some(prim) = part.primitives().next() {
                    for target in prim.morph_targets() {
                        match target.positions() {
                            Some(a) => t.accessor(&a),
                            None => t.add(vertices.saturating_mul(24)),
                        }
                        t.add(vertices.saturating_mul(24));
                    }
                }
                for (input, _) in samplers(part) {
                    t.add((input.count() as u64).saturating_mul(rig).saturating_mul(8));
                }
            }
        }
    }
    if t.bytes > budget {
        return Err(IoError::content(
            path,
            format!(
                "reading {} would decode about {} ({} uses of accessors and compressed views, \
                 {views} of them compressed views), more than the {} a glTF file may decode; \
                 the file reuses its data too often or declares more than it holds",
                super::read::mesh_label(mesh),
                gib(t.bytes),
                t.uses,
                gib(budget)
            ),
        ));
    }
    Ok(())
}
