//! The part of an object's box that no view saw into: cells behind the object's observed surface
//! that no ray passed through.
//!
//! A camera that sees an object from one side sees its near surface, and the rays of the pixels
//! around it pass through the free space beside it; what lies behind the surface, inside the box
//! fitted to the observed cloud, was never seen free. A field left to itself extrapolates there
//! and often leaves it empty (a nightstand seen from behind and above: its lower front curves in
//! under the top). The solid prior (`fields.object_rays.hidden_solid_rays`) asks the field to be
//! solid in these cells, and nowhere a ray passed.
//!
//! The box is divided into [`CELLS_PER_AXIS`]³ cells. Each cell centre is projected into every
//! keyframe crop of the object; at the pixel it lands on (measured depth d, the centre's camera
//! depth z, `m` the cell's half diagonal) the view says:
//! - z < d − m: a ray passed through the cell before its surface — **free**;
//! - |z − d| ≤ m on the object's pixel: the cell is **at the object's surface**;
//! - z > d + m on the object's pixel: **behind the object's surface**;
//! - z > d + m on another object's (or the background's) pixel: **behind another surface** — the
//!   floor under the object, a chair under a table's top: it may be empty.
//!
//! Over all views a cell is, in this order of precedence: seen free (free in one view), occluded
//! (behind another surface in one), surface, hidden (behind the object's surface in one), or
//! unknown. Cells that project outside a crop or onto invalid depth learn nothing from that view.
//! The box is the one fitted to the observed cloud (not the larger region the object is meshed
//! in): its faces are where the object was seen to end. Which hidden cells the prior takes is
//! [`HiddenCells`]' choice; the support prior's samples lie under the box
//! ([`HiddenSpace::draw_below_support`]).
//!
//! The cells seen free feed the seen-free prior (`fields.object_rays.seen_free_rays`): samples
//! around their centres ([`HiddenSpace::draw_free`]) asked to be empty. The rays that saw them
//! free are among the keyframe rays the field trains on anyway, but a step draws few of them
//! (the space under a nightstand's bottom panel, seen through its legs from a few views); the
//! prior gives that evidence the same weight as the hidden cells', so that the solid prior
//! cannot fill what was seen through (a lamp's base disc, under a panel).

use nalgebra::{Isometry3, Point3, Vector3};
use rand::{Rng, RngExt};

use super::object_view::{ObjectView, PixelState};
use crate::geometry::oriented_box::OrientedBox;
use crate::ids::FrameIndex;

/// Cells along each edge of the box.
pub const CELLS_PER_AXIS: usize = 16;

/// Thickness of the slab under the box whose samples are asked to be empty, metres.
pub const BELOW_SUPPORT_M: f32 = 0.06;

/// Gap between the box's bottom face and that slab, metres.
pub const SUPPORT_GAP_M: f32 = 0.01;

/// The span, as a share of a cell's edge, of the draws around a seen-free cell's centre.
pub const FREE_DRAW_SPREAD: f32 = 0.5;

/// Which hidden cells the solid prior asks to be solid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HiddenCells {
    /// Every hidden cell.
    All,
    /// Hidden cells enclosed sideways: walking from the cell along box x or y (both ways)
    /// through hidden cells, no walk ends at a cell seen free or occluded. Space under a
    /// tabletop opens sideways onto space seen between its legs or hidden by the chairs under
    /// it; the inside of a carcass seen from behind ends at its observed panels or at the
    /// box's faces.
    #[default]
    Enclosed,
}

/// The evidence of every cell of a box, x fastest.
struct EvidenceGrid {
    /// Cells per edge.
    n: usize,
    /// Evidence per cell.
    evidence: Vec<CellEvidence>,
}

impl EvidenceGrid {
    fn at(&self, i: usize, j: usize, k: usize) -> CellEvidence {
        self.evidence[(k * self.n + j) * self.n + i]
    }

    /// Whether a walk from hidden cell (i, j, k) along ±x or ±y through hidden cells ends at a
    /// cell seen free or occluded (a walk that leaves the box, or ends at the object's surface or
    /// an unknown cell, does not).
    fn open_sideways(&self, i: usize, j: usize, k: usize) -> bool {
        let n = self.n as isize;
        [(1isize, 0isize), (-1, 0), (0, 1), (0, -1)].iter().any(|&(di, dj)| {
            let (mut x, mut y) = (i as isize + di, j as isize + dj);
            while (0..n).contains(&x) && (0..n).contains(&y) {
                match self.at(x as usize, y as usize, k) {
                    CellEvidence::Hidden => (x, y) = (x + di, y + dj),
                    CellEvidence::SeenFree | CellEvidence::Occluded => return true,
                    CellEvidence::Surface | CellEvidence::Unknown => return false,
                }
            }
            false
        })
    }
}

/// What the views say of one cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellEvidence {
    /// A ray passed through it before the surface it measured.
    SeenFree,
    /// Not seen free, and behind another surface in some view (the floor under the object, a
    /// chair under a table's top): what is there may be empty.
    Occluded,
    /// At the object's observed surface in some view, and neither seen free nor occluded.
    Surface,
    /// Behind the object's observed surface in some view, and none of the above.
    Hidden,
    /// No view says anything of it.
    Unknown,
}

/// What one view says of one point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ViewEvidence {
    /// Before the measured surface.
    Free,
    /// At the object's surface.
    AtObjectSurface,
    /// Behind the surface of the object.
    BehindObject,
    /// Behind the surface of something else (another object, the background).
    BehindOther,
    /// Outside the crop, on invalid depth, or at the surface.
    Nothing,
}

/// The hidden cells of one object's box, ready to draw prior samples from.
#[derive(Debug, Clone, PartialEq)]
pub struct HiddenSpace {
    /// The box the cells divide.
    pub world_from_box: Isometry3<f32>,
    /// Edge lengths of one cell (box extents / [`CELLS_PER_AXIS`]).
    pub cell_size: Vector3<f32>,
    /// Centres of the hidden cells, box frame, in cell order (x fastest).
    pub centres: Vec<Point3<f32>>,
    /// Centres of the cells seen free, box frame, in cell order.
    pub free_centres: Vec<Point3<f32>>,
}

/// What `view` says of the point `p_world`, `margin_m` being how far from the measured surface
/// a point must lie to be before or behind it.
fn view_evidence(view: &ObjectView, p_world: &Point3<f32>, margin_m: f32) -> ViewEvidence {
    let p_camera = view.world_from_camera.inverse_transform_point(p_world);
    let Some((x, y)) = view.intrinsics.project(&p_camera) else {
        return ViewEvidence::Nothing;
    };
    let (u, v) = (x.round(), y.round());
    if u < 0.0 || v < 0.0 {
        return ViewEvidence::Nothing;
    }
    let Some(i) = view.index_of(u as u32, v as u32) else {
        return ViewEvidence::Nothing;
    };
    let d = view.depth_m[i];
    if !(d.is_finite() && d > 0.0) {
        ViewEvidence::Nothing
    } else if p_camera.z < d - margin_m {
        ViewEvidence::Free
    } else if p_camera.z <= d + margin_m {
        match view.states[i] {
            PixelState::ThisObject => ViewEvidence::AtObjectSurface,
            _ => ViewEvidence::Nothing,
        }
    } else {
        match view.states[i] {
            PixelState::ThisObject => ViewEvidence::BehindObject,
            PixelState::OtherObject => ViewEvidence::BehindOther,
            PixelState::Unknown | PixelState::HiddenSolid | PixelState::BelowSupport | PixelState::SeenFree => {
                ViewEvidence::Nothing
            }
        }
    }
}

/// What all `views` together say of the point: seen free in any view wins, then behind another
/// surface in any (occluded), then at the object's surface in any, then behind it in any
/// (hidden).
pub fn cell_evidence(views: &[&ObjectView], p_world: &Point3<f32>, margin_m: f32) -> CellEvidence {
    let (mut hidden, mut surface, mut occluded) = (false, false, false);
    for view in views {
        match view_evidence(view, p_world, margin_m) {
            ViewEvidence::Free => return CellEvidence::SeenFree,
            ViewEvidence::AtObjectSurface => surface = true,
            ViewEvidence::BehindObject => hidden = true,
            ViewEvidence::BehindOther => occluded = true,
            ViewEvidence::Nothing => {}
        }
    }
    if occluded {
        CellEvidence::Occluded
    } else if surface {
        CellEvidence::Surface
    } else if hidden {
        CellEvidence::Hidden
    } else {
        CellEvidence::Unknown
    }
}

impl HiddenSpace {
    /// The hidden cells of `object_box` (world) given the object's keyframe crops `views`.
    pub fn of_views(views: &[&ObjectView], object_box: &OrientedBox, rule: HiddenCells) -> Self {
        let n = CELLS_PER_AXIS;
        let cell_size = object_box.extents() / n as f32;
        let margin_m = 0.5 * cell_size.norm();
        let corner = Point3::from(-object_box.half_extents);
        let centre_of = |i: usize, j: usize, k: usize| {
            corner + cell_size.component_mul(&Vector3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5))
        };
        let mut evidence = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let world = object_box.world_from_box * centre_of(i, j, k);
                    evidence.push(cell_evidence(views, &world, margin_m));
                }
            }
        }
        let grid = EvidenceGrid { n, evidence };
        let (mut centres, mut free_centres) = (Vec::new(), Vec::new());
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    match grid.at(i, j, k) {
                        CellEvidence::SeenFree => free_centres.push(centre_of(i, j, k)),
                        CellEvidence::Hidden if rule == HiddenCells::All || !grid.open_sideways(i, j, k) => {
                            centres.push(centre_of(i, j, k))
                        }
                        _ => {}
                    }
                }
            }
        }
        Self {
            world_from_box: object_box.world_from_box,
            cell_size,
            centres,
            free_centres,
        }
    }

    /// How many cells the priors draw from.
    pub fn cells(&self) -> PriorCells {
        PriorCells {
            hidden: self.centres.len(),
            seen_free: self.free_centres.len(),
        }
    }

    /// The share of the box's cells that are hidden.
    pub fn hidden_share(&self) -> f64 {
        self.centres.len() as f64 / CELLS_PER_AXIS.pow(3) as f64
    }

    /// A point drawn uniformly from the hidden cells (world frame), `None` when there are none.
    pub fn draw(&self, rng: &mut impl Rng) -> Option<Point3<f32>> {
        self.draw_around(&self.centres, 1.0, rng)
    }

    /// A point drawn near a cell seen free (world frame), `None` when there is none: in the
    /// span [`FREE_DRAW_SPREAD`] × the cell's edges around a free cell's centre. The view saw
    /// the centre free, by the cell's half diagonal before the surface on the centre's pixel;
    /// the cell's corners lie on other pixels, which may see something nearer (a lamp's 3 cm
    /// base in the bottom of a 10 cm cell).
    pub fn draw_free(&self, rng: &mut impl Rng) -> Option<Point3<f32>> {
        self.draw_around(&self.free_centres, FREE_DRAW_SPREAD, rng)
    }

    /// A point drawn uniformly in the span `spread` × the cell's edges around one of `centres`
    /// (box frame), in the world frame; `None` without centres.
    fn draw_around(&self, centres: &[Point3<f32>], spread: f32, rng: &mut impl Rng) -> Option<Point3<f32>> {
        if centres.is_empty() {
            return None;
        }
        let centre = centres[rng.random_range(0..centres.len())];
        let jitter = Vector3::from_fn(|a, _| (rng.random::<f32>() - 0.5) * spread * self.cell_size[a]);
        Some(self.world_from_box * (centre + jitter))
    }

    /// A point drawn uniformly under the box (world frame): in the slab [`BELOW_SUPPORT_M`] below
    /// its bottom face (the lowest the object was seen at, what it stands on), starting
    /// [`SUPPORT_GAP_M`] under it, over the footprint grown by a cell on each side.
    pub fn draw_below_support(&self, rng: &mut impl Rng) -> Point3<f32> {
        let half = self.cell_size * (CELLS_PER_AXIS as f32 / 2.0);
        let x = (rng.random::<f32>() * 2.0 - 1.0) * (half.x + self.cell_size.x);
        let y = (rng.random::<f32>() * 2.0 - 1.0) * (half.y + self.cell_size.y);
        let z = -half.z - SUPPORT_GAP_M - rng.random::<f32>() * BELOW_SUPPORT_M;
        self.world_from_box * Point3::new(x, y, z)
    }
}

/// The cells of one object's box the priors draw from (of [`CELLS_PER_AXIS`]³).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PriorCells {
    /// Cells the solid prior asks to be solid.
    pub hidden: usize,
    /// Cells seen free, asked to be empty around their centres.
    pub seen_free: usize,
}

/// One object's hidden space, recomputed only when its keyframes or its box changed.
#[derive(Debug, Clone, Default)]
pub struct HiddenSpaceCache {
    /// The frames of the views, the box and the rule the space was computed from, and the space.
    computed: Option<((Vec<FrameIndex>, OrientedBox, HiddenCells), HiddenSpace)>,
}

impl HiddenSpaceCache {
    /// The space as last computed, if it was.
    pub fn latest(&self) -> Option<&HiddenSpace> {
        self.computed.as_ref().map(|(_, space)| space)
    }

    /// The hidden space of `object_box` given `views`: the stored one when it was computed from
    /// the same frames and box, else computed now (the same inputs give the same space, so a run
    /// resumed with an empty cache continues bit-identically).
    pub fn current(&mut self, views: &[&ObjectView], object_box: &OrientedBox, rule: HiddenCells) -> &HiddenSpace {
        let key = (views.iter().map(|v| v.frame).collect::<Vec<_>>(), *object_box, rule);
        if self
            .computed
            .as_ref()
            .is_none_or(|(computed_for, _)| *computed_for != key)
        {
            self.computed = None;
        }
        &self
            .computed
            .get_or_insert_with(|| (key, HiddenSpace::of_views(views, object_box, rule)))
            .1
    }
}

#[cfg(test)]
#[path = "hidden_space_tests.rs"]
mod tests;
