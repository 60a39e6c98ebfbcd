//! Options of the interior and of the anchor.

use crate::mesh::Point;

/// Which interior to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum InteriorMode {
    /// No interior vertices: surface springs only (the default; the blend of earlier versions).
    #[default]
    None,
    /// A body-centred cubic lattice inside each closed component (pure Rust).
    Lattice,
    /// A constrained Delaunay tetrahedralization of each closed component by an external
    /// `tetgen` program found on the `PATH` (the paper's choice; AGPL, so only ever run as a
    /// separate process, never linked), see [`tetgen`](super::tetgen). Without `tetgen` on the
    /// `PATH` asking for it is an error naming the reason.
    Tetgen,
}

/// How interior points and internal springs are made (Ma et al. Sec. 3.1).
#[derive(Clone, Debug, PartialEq)]
pub struct InteriorOptions {
    /// Which interior. Default [`InteriorMode::None`].
    pub mode: InteriorMode,
    /// Lattice density: the lattice spacing is $h = 2 \bar e / \text{density}$ with $\bar e$
    /// the component's mean surface edge length in the base. Default `1.0` (spacing two
    /// mean edges, so the interior has a few times fewer vertices than the surface of a
    /// compact shape); `2.0` halves the spacing (8× the interior points). For
    /// [`InteriorMode::Tetgen`] the same length $L = h$ sets the largest tetrahedron volume,
    /// $L^3 / (6\sqrt2)$ (a regular tetrahedron of edge $L$).
    pub density: f64,
    /// Lattice only: interior points closer than `margin · h` to the surface are left out, so that no
    /// internal spring is a sliver against the surface. Default `0.35`.
    pub margin: f64,
    /// Lattice only: each surface vertex is tied to at most this many nearest interior points.
    /// Default `4`.
    pub ties_per_vertex: usize,
    /// Lattice only: …within `tie_radius · h`; ties whose segment leaves the solid are dropped. Default `2.0`.
    pub tie_radius: f64,
    /// Stiffness multiplier of internal springs relative to $k_0$. Default `1.0` (the paper
    /// uses one $k_0$ for every spring).
    pub stiffness: f64,
    /// Stiffness $\kappa$ of the volume term on the interior's tetrahedra (the lattice's, plus
    /// one cone per surface triangle to a tied interior point; or tetgen's), relative to
    /// $k_0$ ([`VolumeTerm`](crate::springs::terms::VolumeTerm)); `0` turns it off. Internal
    /// springs alone do not hold the volume under a large shear (docs/fidelity.md, "Volume under
    /// twist"). Default [`VOLUME_STIFFNESS_DEFAULT`] (10).
    pub volume: f64,
}

/// The default [`InteriorOptions::volume`].
pub const VOLUME_STIFFNESS_DEFAULT: f64 = 10.0;

impl Default for InteriorOptions {
    fn default() -> Self {
        Self {
            mode: InteriorMode::None,
            density: 1.0,
            margin: 0.35,
            ties_per_vertex: 4,
            tie_radius: 2.0,
            stiffness: 1.0,
            volume: VOLUME_STIFFNESS_DEFAULT,
        }
    }
}

/// Where the anchor goes.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum AnchorPlacement {
    /// No anchor (the default).
    #[default]
    None,
    /// In the largest closed component: at its volume centroid when that lies inside at
    /// least half as deep as the component's deepest point (on a 24³ grid), else at that
    /// deepest point (nearest the centroid among equals); the cube's edge is half the
    /// clearance to the surface, at most 5% of the bounding-box diagonal. Open meshes: at the
    /// vertex centroid, edge 2% of the diagonal.
    Auto,
    /// At `center` with edge length `size` (`None`: as for `Auto`).
    At {
        /// Centre of the anchor, in base coordinates.
        center: Point,
        /// Edge length of the anchor cube.
        size: Option<f64>,
    },
}

/// The rigid anchor of Ma et al. Sec. 3.4: a small cube of 8 vertices inside the base whose
/// own edges are very stiff and whose vertices are the boundary conditions of the blend.
#[derive(Clone, Debug, PartialEq)]
pub struct AnchorOptions {
    /// Where. Default [`AnchorPlacement::None`].
    pub placement: AnchorPlacement,
    /// Stiffness multiplier of the anchor's own edges relative to $k_0$ ("a very large spring
    /// constant", step 2). Default `1000`.
    pub stiffness: f64,
    /// Each anchor vertex is tied to this many nearest body vertices (interior points where
    /// there are any, else surface vertices) at stiffness $k_0$. Default `8`.
    pub ties_per_vertex: usize,
}

impl Default for AnchorOptions {
    fn default() -> Self {
        Self {
            placement: AnchorPlacement::None,
            stiffness: 1000.0,
            ties_per_vertex: 8,
        }
    }
}

impl InteriorOptions {
    /// Parses `none|lattice|tetgen[,density[,volume]]` (the `--interior` flag and the scene
    /// file's `blend.interior`; `volume` is [`Self::volume`], 0 turns the volume term off);
    /// other fields keep their defaults. The error says what is wrong.
    pub fn parse(spec: &str) -> Result<Self, String> {
        let mut parts = spec.split(',');
        let mode = match parts.next().unwrap_or("").trim() {
            "none" => InteriorMode::None,
            "lattice" => InteriorMode::Lattice,
            "tetgen" => InteriorMode::Tetgen,
            other => {
                return Err(format!(
                    "unknown kind '{other}'; use none, lattice or tetgen, optionally followed by ,density"
                ))
            }
        };
        let mut o = Self {
            mode,
            ..Default::default()
        };
        if let Some(d) = parts.next() {
            o.density = d
                .trim()
                .parse()
                .map_err(|_| format!("density '{d}' is not a number"))?;
            if !(o.density.is_finite() && o.density > 0.0) {
                return Err(format!("the density must be positive, got {d}"));
            }
        }
        if let Some(v) = parts.next() {
            o.volume = v
                .trim()
                .parse()
                .map_err(|_| format!("volume stiffness '{v}' is not a number"))?;
            if !(o.volume.is_finite() && o.volume >= 0.0) {
                return Err(format!(
                    "the volume stiffness must be 0 or positive, got {v}"
                ));
            }
        }
        if parts.next().is_some() {
            return Err(format!("takes KIND[,density[,volume]], got '{spec}'"));
        }
        Ok(o)
    }

    pub(crate) fn check(&self) -> Result<(), super::InteriorError> {
        let bad = |what: &str, v: f64| {
            Err(super::InteriorError::InvalidOption(format!(
                "{what} must be finite and positive, got {v}"
            )))
        };
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad("the interior density", self.density);
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return bad("the margin", self.margin);
        }
        if !(self.tie_radius.is_finite() && self.tie_radius > 0.0) {
            return bad("the tie radius", self.tie_radius);
        }
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return bad("the internal stiffness", self.stiffness);
        }
        if !(self.volume.is_finite() && self.volume >= 0.0) {
            return Err(super::InteriorError::InvalidOption(format!(
                "the volume stiffness must be finite and not negative, got {}",
                self.volume
            )));
        }
        Ok(())
    }
}

impl AnchorOptions {
    /// Parses `auto|x,y,z[,size]` (the `--anchor` flag and the scene file's `blend.anchor`);
    /// other fields keep their defaults.
    pub fn parse(spec: &str) -> Result<Self, String> {
        let placement = match spec.trim() {
            "auto" => AnchorPlacement::Auto,
            s => {
                let v: Vec<f64> = s
                    .split(',')
                    .map(|x| x.trim().parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| format!("'{s}' is not auto or x,y,z[,size]"))?;
                if !(v.len() == 3 || v.len() == 4) || v.iter().any(|x| !x.is_finite()) {
                    return Err(format!(
                        "takes auto or x,y,z[,size] (finite numbers), got '{s}'"
                    ));
                }
                AnchorPlacement::At {
                    center: [v[0], v[1], v[2]],
                    size: v.get(3).copied(),
                }
            }
        };
        Ok(Self {
            placement,
            ..Default::default()
        })
    }

    pub(crate) fn check(&self) -> Result<(), super::InteriorError> {
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return Err(super::InteriorError::InvalidOption(format!(
                "the anchor stiffness must be finite and positive, got {}",
                self.stiffness
            )));
        }
        if let AnchorPlacement::At { center, size } = &self.placement {
            if center.iter().any(|c| !c.is_finite())
                || size.is_some_and(|s| !(s.is_finite() && s > 0.0))
            {
                return Err(super::InteriorError::InvalidOption(format!(
                    "the anchor needs a finite centre and a finite positive size, got {center:?}, {size:?}"
                )));
            }
        }
        if self.ties_per_vertex == 0 {
            return Err(super::InteriorError::InvalidOption(
                "the anchor needs at least one tie per vertex".into(),
            ));
        }
        Ok(())
    }
}
