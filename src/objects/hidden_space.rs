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
//! The box is divided into [`CELLS_PER_AXIS`]³ cells; what the keyframe crops say of each
//! cell's centre is [`super::cell_evidence`]'s: seen free, occluded, at the object's surface,
//! glimpsed, hidden or unknown.
//!
//! The box is the one fitted to the observed cloud (not the larger region the object is meshed
//! in): its faces are where the object was seen to end. It is stood upright first
//! ([`OrientedBox::upright`]): a box fitted to a partly seen object may lean, and the walks
//! below go sideways, along the floor; in a leaning box they climb from the gap under a sofa
//! into its base. Which hidden cells the prior takes is [`HiddenCells`]' choice; the support
//! prior's samples lie under the box ([`HiddenSpace::draw_below_support`]).
//!
//! Hidden cells that open sideways onto space a view saw through (seen free or glimpsed) under
//! the object are **open**: the space under a tabletop's apron, between legs, under a bed's
//! frame or a sofa's body. Under [`FreeCells::SeenAndOpen`] they join the seen-free prior's
//! cells (a glimpsed cell does not: the view saw its centre free, not the span its draws
//! cover): what continues space seen empty, behind nothing but the object's own top, is asked to
//! be empty (the field left to itself extends the top into a slab).
//!
//! The cells seen free feed the seen-free prior (`fields.object_rays.seen_free_rays`): samples
//! around their centres ([`HiddenSpace::draw_free`]) asked to be empty. The rays that saw them
//! free are among the keyframe rays the field trains on anyway, but a step draws few of them
//! (the space under a nightstand's bottom panel, seen through its legs from a few views); the
//! prior gives that evidence the same weight as the hidden cells', so that the solid prior
//! cannot fill what was seen through (a lamp's base disc, under a panel).

use nalgebra::{Isometry3, Point3, Vector3};
use rand::{Rng, RngExt};

use super::cell_evidence::{CellEvidence, EvidenceGrid, GLIMPSE_MARGIN_M, ViewEvidence, cell_evidence, view_evidence};
use super::object_view::ObjectView;
use crate::geometry::mirror_symmetry::MirrorPlane;
use crate::geometry::oriented_box::OrientedBox;
use crate::ids::FrameIndex;

pub use super::cell_rules::{CellRules, FreeCells, HiddenCells, UnseenCells};

/// Cells along each edge of the box.
pub const CELLS_PER_AXIS: usize = 16;

/// Thickness of the slab under the box whose samples are asked to be empty, metres.
pub const BELOW_SUPPORT_M: f32 = 0.06;

/// Gap between the box's bottom face and that slab, metres.
pub const SUPPORT_GAP_M: f32 = 0.01;

/// The span, as a share of a cell's edge, of the draws around a seen-free cell's centre.
pub const FREE_DRAW_SPREAD: f32 = 0.5;

/// Draws around a seen-free or open cell's centre before the centre itself is taken.
pub const FREE_DRAW_TRIES: usize = 4;

/// How far from the object's surface, as a view sees it, a free draw must lie, metres of camera
/// depth.
pub const FREE_CLEARANCE_M: f32 = 0.03;

/// The hidden cells of one object's box, ready to draw prior samples from.
#[derive(Debug, Clone, PartialEq)]
pub struct HiddenSpace {
    /// The box the cells divide: the fitted box stood upright.
    pub world_from_box: Isometry3<f32>,
    /// Edge lengths of one cell (box extents / [`CELLS_PER_AXIS`]).
    pub cell_size: Vector3<f32>,
    /// Centres of the hidden cells, box frame, in cell order (x fastest).
    pub centres: Vec<Point3<f32>>,
    /// Centres of the cells seen free, box frame, in cell order.
    pub free_centres: Vec<Point3<f32>>,
    /// Centres of the open hidden cells the seen-free prior draws around too (under
    /// [`FreeCells::SeenAndOpen`]; else none), box frame, in cell order.
    pub open_centres: Vec<Point3<f32>>,
    /// Centres of the ring cells beyond the box the seen-free prior draws around too (under
    /// [`FreeCells::SeenOpenAndBeyond`]; else none), box frame, in cell order.
    pub beyond_centres: Vec<Point3<f32>>,
}

impl HiddenSpace {
    /// The prior cells of `object_box` (world) given the object's keyframe crops `views`, picked
    /// by `rules`; `mirror` is the object's mirror plane, if it has one (ring cells whose image
    /// lies in the box are not taken).
    pub fn of_views(
        views: &[&ObjectView],
        object_box: &OrientedBox,
        mirror: Option<&MirrorPlane>,
        rules: CellRules,
    ) -> Self {
        let object_box = &object_box.upright();
        let n = CELLS_PER_AXIS;
        let cell_size = object_box.extents() / n as f32;
        let margin_m = 0.5 * cell_size.norm();
        let centre_of = |i: usize, j: usize, k: usize| cell_centre(object_box, [i, j, k].map(|a| a as isize));
        let mut evidence = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let world = object_box.world_from_box * centre_of(i, j, k);
                    evidence.push(cell_evidence(views, &world, margin_m));
                }
            }
        }
        let mut grid = EvidenceGrid { n, evidence };
        if rules.unseen == UnseenCells::HiddenUnderTheObject {
            grid.hide_unseen_under_the_object();
        }
        let (mut centres, mut free_centres, mut open_centres) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let open_free = rules.free != FreeCells::Seen;
                    match grid.at(i, j, k) {
                        CellEvidence::SeenFree => free_centres.push(centre_of(i, j, k)),
                        CellEvidence::Hidden => {
                            if rules.hidden == HiddenCells::All || !grid.open_sideways(i, j, k) {
                                centres.push(centre_of(i, j, k))
                            } else if open_free && grid.opens_under_the_object(i, j, k) {
                                open_centres.push(centre_of(i, j, k))
                            }
                        }
                        _ => {}
                    }
                }
            }
        }
        let beyond_centres = if rules.free == FreeCells::SeenOpenAndBeyond {
            ring_cells_beyond(views, object_box, mirror, margin_m)
        } else {
            Vec::new()
        };
        Self {
            world_from_box: object_box.world_from_box,
            cell_size,
            centres,
            free_centres,
            open_centres,
            beyond_centres,
        }
    }

    /// How many cells the priors draw from.
    pub fn cells(&self) -> PriorCells {
        PriorCells {
            hidden: self.centres.len(),
            seen_free: self.free_centres.len(),
            open: self.open_centres.len(),
            beyond: self.beyond_centres.len(),
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

    /// Whether the seen-free prior has cells to draw from.
    pub fn has_free_cells(&self) -> bool {
        !(self.free_centres.is_empty() && self.open_centres.is_empty() && self.beyond_centres.is_empty())
    }

    /// A point drawn near a cell seen free, an open cell or a ring cell beyond the box (world
    /// frame, one cell drawn uniformly from all), `None` when there is none: in the span
    /// [`FREE_DRAW_SPREAD`] × the cell's edges around its centre, checked against `views`.
    /// No point is kept that a view sees within [`FREE_CLEARANCE_M`] of the object's surface:
    /// the keyframe rays' surface samples teach the surface, and free draws packed around a
    /// lamp's 2.6 cm pole (the cells beside it are seen free) outweigh the few rays that hit it.
    /// A view saw a seen-free cell's centre free, by the cell's half diagonal before the surface
    /// on the centre's pixel; the span's other points lie on other pixels, which may see
    /// something nearer: a point around a seen-free centre is kept only when a view also sees it
    /// free by [`GLIMPSE_MARGIN_M`]. No view saw into an open or ring cell. After
    /// [`FREE_DRAW_TRIES`] misses the centre itself is taken.
    pub fn draw_free(&self, views: &[&ObjectView], rng: &mut impl Rng) -> Option<Point3<f32>> {
        let (seen, open) = (self.free_centres.len(), self.open_centres.len());
        let all = seen + open + self.beyond_centres.len();
        if all == 0 {
            return None;
        }
        let pick = rng.random_range(0..all);
        let (centre, seen_cell) = if pick < seen {
            (self.free_centres[pick], true)
        } else if pick < seen + open {
            (self.open_centres[pick - seen], false)
        } else {
            (self.beyond_centres[pick - seen - open], false)
        };
        for _ in 0..FREE_DRAW_TRIES {
            let p = self.around(centre, FREE_DRAW_SPREAD, rng);
            let near_surface = views
                .iter()
                .any(|v| view_evidence(v, &p, FREE_CLEARANCE_M) == ViewEvidence::AtObjectSurface);
            let seen_free = || {
                views
                    .iter()
                    .any(|v| view_evidence(v, &p, GLIMPSE_MARGIN_M) == ViewEvidence::Free)
            };
            if !near_surface && (!seen_cell || seen_free()) {
                return Some(p);
            }
        }
        Some(self.world_from_box * centre)
    }

    /// A point drawn uniformly in the span `spread` × the cell's edges around one of `centres`
    /// (box frame), in the world frame; `None` without centres.
    fn draw_around(&self, centres: &[Point3<f32>], spread: f32, rng: &mut impl Rng) -> Option<Point3<f32>> {
        if centres.is_empty() {
            return None;
        }
        let centre = centres[rng.random_range(0..centres.len())];
        Some(self.around(centre, spread, rng))
    }

    /// A point drawn uniformly in the span `spread` × the cell's edges around `centre` (box
    /// frame), in the world frame.
    fn around(&self, centre: Point3<f32>, spread: f32, rng: &mut impl Rng) -> Point3<f32> {
        let jitter = Vector3::from_fn(|a, _| (rng.random::<f32>() - 0.5) * spread * self.cell_size[a]);
        self.world_from_box * (centre + jitter)
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

/// The centre (box frame) of cell `(i, j, k)` of `object_box`'s grid of [`CELLS_PER_AXIS`]³
/// cells; indices outside `0..CELLS_PER_AXIS` name cells beyond the box.
fn cell_centre(object_box: &OrientedBox, [i, j, k]: [isize; 3]) -> Point3<f32> {
    let cell_size = object_box.extents() / CELLS_PER_AXIS as f32;
    let index = Vector3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5);
    Point3::from(-object_box.half_extents) + cell_size.component_mul(&index)
}

/// Centres (box frame of the upright `object_box`, cells of its grid) of the ring one cell
/// thick around its sides and top whose evidence in `views` is hidden or glimpsed, and whose
/// image across `mirror` is outside the box ([`FreeCells::SeenOpenAndBeyond`]).
fn ring_cells_beyond(
    views: &[&ObjectView],
    object_box: &OrientedBox,
    mirror: Option<&MirrorPlane>,
    margin_m: f32,
) -> Vec<Point3<f32>> {
    let n = CELLS_PER_AXIS as isize;
    let inside = |a: isize| (0..n).contains(&a);
    let mut centres = Vec::new();
    for k in 0..=n {
        for j in -1..=n {
            for i in -1..=n {
                if inside(i) && inside(j) && inside(k) {
                    continue;
                }
                let centre = cell_centre(object_box, [i, j, k]);
                let world = object_box.world_from_box * centre;
                if mirror.is_some_and(|plane| object_box.contains(&plane.reflect(&world), 0.0)) {
                    continue;
                }
                if matches!(
                    cell_evidence(views, &world, margin_m),
                    CellEvidence::Hidden | CellEvidence::Glimpsed
                ) {
                    centres.push(centre);
                }
            }
        }
    }
    centres
}

/// The cells of one object's box the priors draw from (of [`CELLS_PER_AXIS`]³).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PriorCells {
    /// Cells the solid prior asks to be solid.
    pub hidden: usize,
    /// Cells seen free, asked to be empty around their centres.
    pub seen_free: usize,
    /// Open hidden cells, asked to be empty around their centres.
    #[serde(default)]
    pub open: usize,
    /// Ring cells beyond the box, asked to be empty around their centres.
    #[serde(default)]
    pub beyond: usize,
}

/// What a hidden space is computed from: the frames of the views, the box, the mirror plane and
/// the rules.
type HiddenSpaceKey = (Vec<FrameIndex>, OrientedBox, Option<MirrorPlane>, CellRules);

/// One object's hidden space, recomputed only when its keyframes, its box or its plane changed.
#[derive(Debug, Clone, Default)]
pub struct HiddenSpaceCache {
    /// What the space was computed from, and the space.
    computed: Option<(HiddenSpaceKey, HiddenSpace)>,
}

impl HiddenSpaceCache {
    /// The space as last computed, if it was.
    pub fn latest(&self) -> Option<&HiddenSpace> {
        self.computed.as_ref().map(|(_, space)| space)
    }

    /// The hidden space of `object_box` given `views`: the stored one when it was computed from
    /// the same frames and box, else computed now (the same inputs give the same space, so a run
    /// resumed with an empty cache continues bit-identically).
    pub fn current(
        &mut self,
        views: &[&ObjectView],
        object_box: &OrientedBox,
        mirror: Option<&MirrorPlane>,
        rules: CellRules,
    ) -> &HiddenSpace {
        let key = (
            views.iter().map(|v| v.frame).collect::<Vec<_>>(),
            *object_box,
            mirror.copied(),
            rules,
        );
        if self
            .computed
            .as_ref()
            .is_none_or(|(computed_for, _)| *computed_for != key)
        {
            self.computed = None;
        }
        &self
            .computed
            .get_or_insert_with(|| (key, HiddenSpace::of_views(views, object_box, mirror, rules)))
            .1
    }
}

#[cfg(test)]
#[path = "hidden_space_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "hidden_space_beyond_tests.rs"]
mod beyond_tests;
#[cfg(test)]
#[path = "hidden_space_draw_tests.rs"]
mod draw_tests;
#[cfg(test)]
#[path = "hidden_space_open_tests.rs"]
mod open_tests;
