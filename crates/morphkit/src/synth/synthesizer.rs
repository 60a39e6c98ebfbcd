//! The stateful synthesizer: layers of partial animations on one target, prefactored once
//! (Wang & Lee 2008, Sec. 3.2.2–3.2.4).
//!
//! Output frame $f$ is built per target triangle $t$ from the bottom up:
//! 1. $G_t$ = the **rest layer**: the identity (the target's own reference pose), or the
//!    gradient of a given rest pose;
//! 2. for each layer $k$ in recipe order that is active at $f$, with its transferred source
//!    gradient $L_{kt}$ (the layer's source frame at time $f$ through its correspondence) and
//!    weight $w_{kt}$: $G_t \leftarrow$ blend or compound ([`super::BlendMode`]);
//! 3. the pose edits: $N_t = G_t P_t$ ([`super::pose`]);
//! 4. one prefactored solve ([`TransferSolver::solve`]) and the translation convention of the
//!    *follow* layer ([`Placement`]).
//!
//! **As transfer does** (issue 55). Each layer carries its source gradients onto the target as
//! [`AnimationTransfer`](crate::transfer::AnimationTransfer) does with the same
//! [`TransferOptions`] ([`SynthOptions::transfer`], default [`TransferOptions::default`]): in
//! the local-stretch frame by default, the solve area-weighted and each target triangle's term
//! weighted by its matches' confidence, and a frame that creases guarded as
//! [`fold_guard`](crate::transfer::fold_guard) describes (the unturned alternative is the same
//! layering of every layer's unturned gradients). The solve is factored once, so the
//! confidence of triangle $t$ is fixed: starting from 1 (the rest layer), each layer in recipe
//! order mixes in its own, $c_t \leftarrow (1 - w_{kt})\,c_t + w_{kt}\,c_{kt}$, whatever its
//! mode and timing. One layer of weight 1 everywhere is therefore plain transfer.
//!
//! **Timing.** Layer $k$ drives output frames from `offset` on at `speed` source frames per
//! output frame: source time $s = (f - \text{offset}) \cdot \text{speed}$. A fractional $s$
//! blends the two neighbouring source frames' gradients ([`super::blend_gradient`]). With
//! `looped` the time wraps modulo the frame count (the last frame blends into the first);
//! otherwise the layer is inactive outside $[0, n-1]$ and its region falls back to the layers
//! below. A single-frame layer is a pose: it holds from `offset` on.
//!
//! **Contradiction.** A `blend` layer at weight exactly 1 replaces whatever is below it, so a
//! later blend layer that fully covers triangles an earlier layer (of either mode) also drives
//! at weight 1, on an output frame where both are active, would silently erase the earlier
//! one: [`Synthesizer::new`] refuses that ([`SynthError::ContradictingLayers`]). A later
//! compound layer multiplies onto what is below (the paper's Fig. 10) and never contradicts.

use super::geodesic::{geodesic_weights, HeatGeodesics, HeatOptions};
use super::gradient_blend::{apply_layer, blend_gradient, BlendMode};
use super::layer::Carried;
use super::layer::{check_contradictions, check_layer, Layer};
use super::pose::{rotation_gradients, PoseEditor};
use super::{
    BlendWeights, Flexibility, FlexibilityAccumulator, Partitions, Selection, SynthError,
    WeightSolver, GAMMA, KAPPA,
};
use crate::mesh::{Point, Topology, TriMesh};
use crate::transfer::animation::unit_normals;
use crate::transfer::fold_guard::guarded_solve;
use crate::transfer::gradients::FlipCheck;
use crate::transfer::{
    Correspondence, FoldGuard, GradientFrame, GradientOperator, GuardOutcome, Placement,
    TransferOptions, TransferSolver,
};
use nalgebra::{Matrix3, Vector3};
use std::time::Instant;

/// How a layer's weights are found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum BlendRegion {
    /// Intelligent scribbling over stiff/flexible partitions and Eq. 5 (Sec. 3.2.1–3.2.2).
    #[default]
    Partitions,
    /// Geodesic band of this total width (mesh units) around the scribble's boundary (Sec. 4).
    Geodesic {
        /// Band width, target mesh units.
        width: f64,
    },
}

/// When a layer plays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// First output frame the layer drives. Default 0.
    pub offset: usize,
    /// Source frames per output frame, positive. Default 1.
    pub speed: f64,
    /// Wrap the source time around. Default false.
    pub looped: bool,
}

impl Default for Timing {
    fn default() -> Self {
        Self {
            offset: 0,
            speed: 1.0,
            looped: false,
        }
    }
}

/// One layer, in memory.
#[derive(Clone, Debug)]
pub struct LayerSpec {
    /// The source reference pose the frames' gradients are measured from.
    pub source_reference: TriMesh,
    /// Source frames (positions over the source reference's connectivity), at least one.
    pub frames: Vec<Vec<Point>>,
    /// Source → target correspondence.
    pub correspondence: Correspondence,
    /// Scribbled target triangles (one entry per target triangle).
    pub scribble: Vec<bool>,
    /// Blend or compound.
    pub mode: BlendMode,
    /// When it plays.
    pub timing: Timing,
    /// Partitions or a geodesic band.
    pub region: BlendRegion,
}

/// One pose edit, in memory.
#[derive(Clone, Debug)]
pub struct PoseSpec {
    /// Scribbled target triangles.
    pub scribble: Vec<bool>,
    /// Layer whose partitions refine the scribble.
    pub layer: usize,
    /// Rotation axis (world coordinates).
    pub axis: [f64; 3],
    /// Rotation angle, radians.
    pub angle: f64,
}

/// Options of [`Synthesizer`].
#[derive(Clone, Debug)]
pub struct SynthOptions {
    /// Output frame count. Default 1.
    pub frames: usize,
    /// Flexibility threshold γ. Default 0.1 (the paper's).
    pub gamma: f64,
    /// Soft-constraint weight κ of Eq. 5. Default 10 000 (the paper's).
    pub kappa: f64,
    /// How every layer is transferred (the solve's weights and constraint vertices, how
    /// matched gradients combine, the frame they are carried in, the fold guard) and the
    /// translation (follow a layer's markers or keep the constraint vertex fixed). Default:
    /// [`TransferOptions::default`], the defaults of `morphkit transfer`, so that a synthesis
    /// with one whole-target layer is plain transfer (issue 55).
    pub transfer: TransferOptions,
    /// Layer whose source motion the target's translation follows. Default `None`: the layer
    /// with the largest total weight (the first on a tie).
    pub follow_layer: Option<usize>,
    /// A rest pose of the target (positions over its connectivity) under every layer.
    /// Default `None`: the target's reference.
    pub rest: Option<Vec<Point>>,
}

impl Default for SynthOptions {
    fn default() -> Self {
        Self {
            frames: 1,
            gamma: GAMMA,
            kappa: KAPPA,
            transfer: TransferOptions::default(),
            follow_layer: None,
            rest: None,
        }
    }
}

/// What was decided for one layer, and how long it took.
#[derive(Clone, Debug)]
pub struct LayerInfo {
    /// Target flexibility through the correspondence.
    pub flexibility: Flexibility,
    /// Partitions by γ.
    pub partitions: Partitions,
    /// Refined selection (partitions mode; for geodesic, the weight-1 triangles).
    pub selection: Selection,
    /// Blend weights.
    pub weights: BlendWeights,
    /// Seconds for flexibility, partitions and weights.
    pub weights_seconds: f64,
}

/// One synthesised frame.
#[derive(Clone, Debug)]
pub struct SynthFrame {
    /// Target positions.
    pub positions: Vec<Point>,
    /// The wanted gradients $N_t$ the solve matched.
    pub gradients: Vec<Matrix3<f64>>,
    /// Seconds spent computing and blending the layers' gradients.
    pub blend_seconds: f64,
    /// Seconds in the solve and placement.
    pub solve_seconds: f64,
    /// What the fold guard did (local-stretch frame only).
    pub guard: GuardOutcome,
}

/// Layers and pose edits on one target, factored once; then frame after frame.
#[derive(Debug)]
pub struct Synthesizer {
    target: TriMesh,
    solver: TransferSolver,
    layers: Vec<Layer>,
    rest: Vec<Matrix3<f64>>,
    pose: Option<Vec<Matrix3<f64>>>,
    flips: FlipCheck,
    follow: Option<usize>,
    frames: usize,
    factor_seconds: f64,
    opts: TransferOptions,
    /// Unit normals of the target reference's triangles (local-stretch frame only).
    target_normals: Option<Vec<Vector3<f64>>>,
    /// The fold guard and the target's topology (local-stretch frame only).
    guard: Option<(FoldGuard, Topology)>,
}

fn layer_info(
    spec: &LayerSpec,
    k: usize,
    target: &TriMesh,
    topology: &Topology,
    heat: &mut Option<HeatGeodesics>,
    opts: &SynthOptions,
) -> Result<(LayerInfo, Option<WeightSolver>), SynthError> {
    let t0 = Instant::now();
    let op = GradientOperator::new(&spec.source_reference);
    let stopo = Topology::new(
        spec.source_reference.num_vertices(),
        &spec.source_reference.triangles,
    );
    let mut acc = FlexibilityAccumulator::new(&stopo, spec.source_reference.num_triangles());
    for (i, f) in spec.frames.iter().enumerate() {
        let g = op
            .gradients_at(i, f)
            .map_err(|source| SynthError::Layer { layer: k, source })?;
        acc.add(&g)?;
    }
    let flexibility = acc.finish().map_to_target(&spec.correspondence)?;
    let partitions = Partitions::new(&flexibility, topology, opts.gamma)?;
    let (selection, weights, solver) = match spec.region {
        BlendRegion::Partitions => {
            let selection = Selection::refine(&partitions, &spec.scribble)?;
            let solver = WeightSolver::new(topology, &partitions.stiff_mask(), opts.kappa)?;
            let weights = solver.solve(&selection.triangles)?;
            (selection, weights, Some(solver))
        }
        BlendRegion::Geodesic { width } => {
            if heat.is_none() {
                *heat = Some(HeatGeodesics::new(target, &HeatOptions::default())?);
            }
            let h = heat.as_ref().expect("built above");
            let (weights, _) =
                geodesic_weights(target, topology, h, &spec.scribble, width, opts.kappa)?;
            let triangles: Vec<bool> = weights.values.iter().map(|&w| w == 1.0).collect();
            let selection = Selection {
                partitions: Vec::new(),
                triangles,
            };
            (selection, weights, None)
        }
    };
    let info = LayerInfo {
        flexibility,
        partitions,
        selection,
        weights,
        weights_seconds: t0.elapsed().as_secs_f64(),
    };
    Ok((info, solver))
}

impl Synthesizer {
    /// Validates the layers, computes every layer's partitions and weights, applies the pose
    /// edits and factors the target's transfer matrix once.
    pub fn new(
        target: &TriMesh,
        layers: Vec<LayerSpec>,
        poses: &[PoseSpec],
        opts: &SynthOptions,
    ) -> Result<Self, SynthError> {
        if opts.frames == 0 {
            return Err(SynthError::Parameter {
                name: "frames",
                value: 0.0,
                why: "at least one output frame",
            });
        }
        let local = opts.transfer.frame == GradientFrame::LocalStretch;
        let target_normals = local.then(|| unit_normals(target));
        let nf = target.num_triangles();
        let topology = Topology::new(target.num_vertices(), &target.triangles);
        let mut heat = None;
        let mut built = Vec::with_capacity(layers.len());
        for (k, spec) in layers.into_iter().enumerate() {
            let in_layer = |e: SynthError| SynthError::InLayer {
                layer: k,
                source: Box::new(e),
            };
            check_layer(&spec, target).map_err(in_layer)?;
            let (info, weight_solver) =
                layer_info(&spec, k, target, &topology, &mut heat, opts).map_err(in_layer)?;
            let mut needed = vec![false; spec.source_reference.num_triangles()];
            for (t, &w) in info.weights.values.iter().enumerate() {
                if w > 0.0 {
                    for &m in spec.correspondence.matches_of(t) {
                        needed[m as usize] = true;
                    }
                }
            }
            built.push(Layer {
                source_normals: local.then(|| unit_normals(&spec.source_reference)),
                needed,
                gradients: GradientOperator::new(&spec.source_reference),
                placement: Placement::new(
                    &spec.source_reference,
                    target,
                    &spec.correspondence,
                    opts.transfer.translation,
                ),
                correspondence: spec.correspondence,
                frames: spec.frames,
                mode: spec.mode,
                timing: spec.timing,
                weight_solver,
                info,
            });
        }
        check_contradictions(&built, opts.frames)?;
        // The confidence of each target triangle's term (module doc), local stretch only.
        let mut confidence = Vec::new();
        if let Some(nt) = &target_normals {
            confidence = vec![1.0; nf];
            for l in &built {
                let ns = l.source_normals.as_ref().expect("local stretch");
                let lc = l
                    .correspondence
                    .local_confidence(ns, nt, opts.transfer.combine);
                for ((c, &w), lc) in confidence.iter_mut().zip(&l.info.weights.values).zip(lc) {
                    *c = (1.0 - w) * *c + w * lc;
                }
            }
        }
        let t0 = Instant::now();
        let solver = TransferSolver::with_confidence(target, &opts.transfer.solver, &confidence)?;
        let factor_seconds = t0.elapsed().as_secs_f64();
        let rest = match &opts.rest {
            Some(p) => GradientOperator::new(target).gradients(p)?,
            None => vec![Matrix3::identity(); nf],
        };
        let follow = match opts.follow_layer {
            Some(k) if k < built.len() => Some(k),
            Some(k) => {
                return Err(SynthError::Parameter {
                    name: "follow_layer",
                    value: k as f64,
                    why: "no such layer",
                })
            }
            None => (0..built.len()).fold(None, |best: Option<usize>, k| {
                let s = |k: usize| built[k].info.weights.values.iter().sum::<f64>();
                match best {
                    Some(b) if s(b) >= s(k) => Some(b),
                    _ => Some(k),
                }
            }),
        };
        let mut synth = Self {
            target: target.clone(),
            solver,
            layers: built,
            rest,
            pose: None,
            flips: FlipCheck::new(target),
            follow,
            frames: opts.frames,
            factor_seconds,
            opts: opts.transfer.clone(),
            guard: match (&target_normals, opts.transfer.fold_guard) {
                (Some(_), Some(g)) => Some((g, topology)),
                _ => None,
            },
            target_normals,
        };
        for (i, p) in poses.iter().enumerate() {
            synth.edit_pose(p).map_err(|e| SynthError::InPose {
                pose: i,
                source: Box::new(e),
            })?;
        }
        Ok(synth)
    }

    /// Applies one more pose edit (Sec. 3.2.4) on top of the earlier ones and returns the
    /// edited reference pose: one weight solve and one transfer solve, no factorization.
    pub fn edit_pose(&mut self, pose: &PoseSpec) -> Result<Vec<Point>, SynthError> {
        let layer = self.layers.get(pose.layer).ok_or(SynthError::Parameter {
            name: "pose layer",
            value: pose.layer as f64,
            why: "no such layer",
        })?;
        let ws = layer.weight_solver.as_ref().ok_or(SynthError::Parameter {
            name: "pose layer",
            value: pose.layer as f64,
            why: "a pose needs a layer with blend_region = \"partitions\"",
        })?;
        let editor = PoseEditor::new(
            &self.solver,
            ws,
            &layer.info.partitions,
            &self.target.triangles,
        )?;
        let selection = Selection::refine(editor.partitions(), &pose.scribble)?;
        let weights = ws.solve(&selection.triangles)?;
        let r = super::pose::axis_angle(pose.axis, pose.angle)?;
        let p = rotation_gradients(&weights, &r);
        let combined: Vec<Matrix3<f64>> = match &self.pose {
            Some(old) => p.iter().zip(old).map(|(a, b)| a * b).collect(),
            None => p,
        };
        let x = editor.solve_pinned(&combined, &weights)?;
        self.pose = Some(combined);
        Ok(x)
    }

    /// Output frame count.
    pub fn num_frames(&self) -> usize {
        self.frames
    }

    /// Number of layers.
    pub fn num_layers(&self) -> usize {
        self.layers.len()
    }

    /// What was decided for layer `k`.
    pub fn layer_info(&self, k: usize) -> &LayerInfo {
        &self.layers[k].info
    }

    /// The layer the translation follows.
    pub fn follow_layer(&self) -> Option<usize> {
        self.follow
    }

    /// Seconds of the one factorization.
    pub fn factor_seconds(&self) -> f64 {
        self.factor_seconds
    }

    /// The prefactored transfer solver.
    pub fn solver(&self) -> &TransferSolver {
        &self.solver
    }

    /// The target reference.
    pub fn target(&self) -> &TriMesh {
        &self.target
    }

    /// The target gradients of layer `k` at output frame `f` (carried as
    /// [`SynthOptions::transfer`] says, turned in the local-stretch frame), or `None` when
    /// inactive.
    pub fn layer_gradients(
        &self,
        k: usize,
        f: usize,
    ) -> Result<Option<Vec<Matrix3<f64>>>, SynthError> {
        Ok(self
            .carried(k, f)?
            .map(|c| self.layers[k].target_gradients(&c, self.target_normals.as_deref(), true)))
    }

    /// Layer `k`'s source gradients at output frame `f` as it carries them, or `None`.
    fn carried(&self, k: usize, f: usize) -> Result<Option<Carried>, SynthError> {
        let layer = &self.layers[k];
        let Some((i, j, frac)) = layer.source_time(f) else {
            return Ok(None);
        };
        let grad = |s: usize| {
            layer
                .gradients
                .gradients_at(s, &layer.frames[s])
                .map_err(|source| SynthError::Layer { layer: k, source })
        };
        let mut g = grad(i)?;
        if frac > 0.0 {
            let next = grad(j)?;
            for ((a, b), _) in g.iter_mut().zip(&next).zip(&layer.needed).filter(|x| *x.1) {
                *a = blend_gradient(a, b, frac);
            }
        }
        Ok(Some(layer.carry(g, self.opts.combine)))
    }

    /// Every layer's carried source gradients at output frame `f`.
    fn all_carried(&self, f: usize) -> Result<Vec<Option<Carried>>, SynthError> {
        (0..self.layers.len()).map(|k| self.carried(k, f)).collect()
    }

    /// The layers' gradients, turned or not, composed (module doc, steps 1–3).
    fn compose(&self, carried: &[Option<Carried>], turned: bool) -> Vec<Matrix3<f64>> {
        let mut g = self.rest.clone();
        for (layer, c) in self.layers.iter().zip(carried) {
            if let Some(c) = c {
                let l = layer.target_gradients(c, self.target_normals.as_deref(), turned);
                apply_layer(&mut g, &l, &layer.info.weights.values, layer.mode);
            }
        }
        if let Some(p) = &self.pose {
            for (a, b) in g.iter_mut().zip(p) {
                *a *= b;
            }
        }
        g
    }

    /// The wanted gradients $N_t$ of output frame `f` (module doc, steps 1–3), before the
    /// fold guard.
    pub fn gradients(&self, f: usize) -> Result<Vec<Matrix3<f64>>, SynthError> {
        Ok(self.compose(&self.all_carried(f)?, true))
    }

    /// Synthesises output frame `f` (0-based, below [`Synthesizer::num_frames`]).
    pub fn frame(&self, f: usize) -> Result<SynthFrame, SynthError> {
        let t0 = Instant::now();
        let carried = self.all_carried(f)?;
        let wanted = self.compose(&carried, true);
        let t1 = Instant::now();
        let solve = |g: &[Matrix3<f64>]| self.solver.solve(g);
        let (mut positions, gradients, guard) = match &self.guard {
            Some((guard, topology)) => guarded_solve(
                guard,
                &self.target,
                topology,
                wanted,
                || self.compose(&carried, false),
                solve,
            )?,
            None => (solve(&wanted)?, wanted, GuardOutcome::default()),
        };
        if let Some(k) = self.follow {
            let layer = &self.layers[k];
            let src = layer
                .source_time(f)
                .map(|(i, _, _)| layer.frames[i].as_slice());
            layer.placement.apply(&mut positions, src);
        }
        Ok(SynthFrame {
            positions,
            gradients,
            blend_seconds: (t1 - t0).as_secs_f64(),
            solve_seconds: t1.elapsed().as_secs_f64(),
            guard,
        })
    }

    /// Triangles of `frame` facing against their wanted gradient ([`FlipCheck::flipped`]).
    pub fn flipped_triangles(&self, frame: &SynthFrame) -> Vec<usize> {
        self.flips.flipped(&frame.positions, &frame.gradients)
    }

    /// Every frame, in order.
    pub fn frames(&self) -> impl Iterator<Item = Result<SynthFrame, SynthError>> + '_ {
        (0..self.frames).map(|f| self.frame(f))
    }
}

/// One-shot synthesis of every output frame.
pub fn synthesize(
    target: &TriMesh,
    layers: Vec<LayerSpec>,
    poses: &[PoseSpec],
    opts: &SynthOptions,
) -> Result<Vec<Vec<Point>>, SynthError> {
    let s = Synthesizer::new(target, layers, poses, opts)?;
    s.frames().map(|r| r.map(|f| f.positions)).collect()
}
