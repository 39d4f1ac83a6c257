//! What an object's keyframe crops say of a point of its box, and of every cell of the box
//! ([`super::hidden_space`]).
//!
//! A box is divided into cells ([`super::hidden_space::CELLS_PER_AXIS`]³). Each cell centre is
//! projected into every keyframe crop of the object; at the pixel it lands on (measured depth d,
//! the centre's camera depth z, `m` the cell's half diagonal) the view says:
//! - z < d − m: a ray passed through the cell before its surface — **free**;
//! - |z − d| ≤ m on the object's pixel: the cell is **at the object's surface**;
//! - z > d + m on the object's pixel: **behind the object's surface**;
//! - z > d + m on another object's (or the background's) pixel, by at most
//!   [`OCCLUDER_DEPTH_M`]: **behind another surface** — the floor under the object, a chair under
//!   a table's top: it may be empty;
//! - d − m ≤ z < d − [`GLIMPSE_MARGIN_M`] on another object's (or the background's) pixel: the
//!   ray passed the centre, if not the whole cell, before the surface behind it — **glimpsed**
//!   (the floor seen under a bed's frame through a 12 cm gap, two cells of 6 cm: their centres
//!   are nearer to the floor than the half diagonal, 9 cm);
//! - on a pixel without depth, not the object's, whose neighbours within
//!   [`NO_RETURN_RADIUS_PX`] have none either: the sensor saw nothing within its range there
//!   (a room's far wall beyond a Kinect's 5 m) — **free**, if the centre lies nearer than the
//!   deepest return of the crop (the sensor reaches at least that far; a sofa's inside 5.2–6 m
//!   from a camera of 5 m range, behind a front beyond the range too, was called free and drawn
//!   hollow); on any other pixel without depth the view says nothing.
//!
//! With a depth camera's noise allowance (`dataset.depth_noise_per_m2`, a × d²), `m` and the
//! glimpse margin grow by a × d² on each view: one view's noisy pixel, a few centimetres deep,
//! does not call a cell inside the object seen free (a storage box seen through a Kinect-like
//! camera had 306 such cells, and its inside, open onto them, was drawn empty).
//!
//! Over all views a cell is, in this order of precedence: seen free (free in one view), occluded
//! (behind another surface in one), surface, glimpsed, hidden (behind the object's surface in
//! one), or unknown. Cells that project outside a crop, or onto a pixel without depth that is
//! not a no-return patch, learn nothing from that view.
//!
//! A hidden cell whose walk sideways (along box x or y, through hidden cells) ends at a cell seen
//! free, glimpsed or occluded opens sideways ([`EvidenceGrid::open_sideways`]); one whose walk
//! ends at a cell seen free or glimpsed under the object (its observed surface, or space hidden
//! behind it, above) continues space seen under the object
//! ([`EvidenceGrid::opens_under_the_object`]).

use nalgebra::Point3;

use super::object_view::{ObjectView, PixelState};

/// How far before the surface on its pixel (another object's or the background's) a cell's
/// centre must lie for the view to have glimpsed through the cell, metres of camera depth.
pub const GLIMPSE_MARGIN_M: f32 = 0.02;

/// Half the edge of the window of pixels without depth that makes a pixel without depth a view
/// of nothing within the sensor's range: a point projecting there is seen free.
pub const NO_RETURN_RADIUS_PX: u32 = 2;

/// How far behind another object's surface a point may be that object's, metres of camera
/// depth: deeper, the view says nothing of it (a sofa's base 1 m behind the armchair in front
/// of it is not the armchair's).
pub const OCCLUDER_DEPTH_M: f32 = 0.6;

/// The evidence of every cell of a box, x fastest.
pub(super) struct EvidenceGrid {
    /// Cells per edge.
    pub(super) n: usize,
    /// Evidence per cell.
    pub(super) evidence: Vec<CellEvidence>,
}

impl EvidenceGrid {
    pub(super) fn at(&self, i: usize, j: usize, k: usize) -> CellEvidence {
        self.evidence[(k * self.n + j) * self.n + i]
    }

    /// The cells where walks from hidden cell (i, j, k) along ±x and ±y through hidden cells end
    /// (none for a walk that leaves the box).
    fn walk_ends(&self, i: usize, j: usize, k: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        let n = self.n as isize;
        [(1isize, 0isize), (-1, 0), (0, 1), (0, -1)]
            .into_iter()
            .filter_map(move |(di, dj)| {
                let (mut x, mut y) = (i as isize + di, j as isize + dj);
                while (0..n).contains(&x) && (0..n).contains(&y) {
                    if self.at(x as usize, y as usize, k) != CellEvidence::Hidden {
                        return Some((x as usize, y as usize));
                    }
                    (x, y) = (x + di, y + dj);
                }
                None
            })
    }

    /// Makes every unknown cell under the object hidden: one whose column holds, above it and
    /// with only unknown cells between, a cell at the object's surface or hidden behind it.
    pub(super) fn hide_unseen_under_the_object(&mut self) {
        let n = self.n;
        for j in 0..n {
            for i in 0..n {
                let mut under_the_object = false;
                for k in (0..n).rev() {
                    let at = (k * n + j) * n + i;
                    match self.evidence[at] {
                        CellEvidence::Surface | CellEvidence::Hidden => under_the_object = true,
                        CellEvidence::Unknown if under_the_object => self.evidence[at] = CellEvidence::Hidden,
                        CellEvidence::Unknown => {}
                        CellEvidence::SeenFree | CellEvidence::Occluded | CellEvidence::Glimpsed => {
                            under_the_object = false
                        }
                    }
                }
            }
        }
    }

    /// Whether hidden cell (i, j, k) opens sideways onto space that may be empty: a walk ends at
    /// a cell seen free, glimpsed, or occluded (not at the object's surface or an unknown cell).
    pub(super) fn open_sideways(&self, i: usize, j: usize, k: usize) -> bool {
        self.walk_ends(i, j, k).any(|(x, y)| {
            matches!(
                self.at(x, y, k),
                CellEvidence::SeenFree | CellEvidence::Glimpsed | CellEvidence::Occluded
            )
        })
    }

    /// Whether hidden cell (i, j, k) continues space seen under the object: a walk ends at a
    /// cell seen free or glimpsed with the object above it — a cell at its observed surface (a
    /// top, a frame, an apron) or hidden behind it (a sofa's body over the floor seen under its
    /// front edge: the body's front face is a row of cells nearer the view). Space behind
    /// another object may hold that object, and space seen beside the object (past the end of a
    /// sofa's back, above its arm) says nothing of the hidden cells inside it, which the walk
    /// crosses when a cell's evidence misses the object's end face.
    pub(super) fn opens_under_the_object(&self, i: usize, j: usize, k: usize) -> bool {
        self.walk_ends(i, j, k).any(|(x, y)| {
            matches!(self.at(x, y, k), CellEvidence::SeenFree | CellEvidence::Glimpsed)
                && (k + 1..self.n)
                    .any(|above| matches!(self.at(x, y, above), CellEvidence::Surface | CellEvidence::Hidden))
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
    /// Its centre before another surface by more than [`GLIMPSE_MARGIN_M`] in some view (not by
    /// the margin that makes the whole cell seen free), and none of the above.
    Glimpsed,
    /// Behind the object's observed surface in some view, and none of the above.
    Hidden,
    /// No view says anything of it.
    Unknown,
}

/// What one view says of one point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ViewEvidence {
    /// Before the measured surface.
    Free,
    /// At the object's surface.
    AtObjectSurface,
    /// Behind the surface of the object.
    BehindObject,
    /// Behind the surface of something else (another object, the background).
    BehindOther,
    /// Before the surface of something else by more than [`GLIMPSE_MARGIN_M`].
    Glimpsed,
    /// Outside the crop, on invalid depth, or at the surface.
    Nothing,
}

/// What `view` says of the point `p_world`, `margin_m` being how far from the measured surface
/// a point must lie to be before or behind it.
pub(crate) fn view_evidence(view: &ObjectView, p_world: &Point3<f32>, margin_m: f32) -> ViewEvidence {
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
        if view.states[i] != PixelState::ThisObject
            && p_camera.z < view.deepest_return_m
            && no_depth_around(view, u as u32, v as u32)
        {
            ViewEvidence::Free
        } else {
            ViewEvidence::Nothing
        }
    } else if p_camera.z < d - margin_m - view.depth_noise_m(d) {
        ViewEvidence::Free
    } else if p_camera.z <= d + margin_m + view.depth_noise_m(d) {
        match view.states[i] {
            PixelState::ThisObject => ViewEvidence::AtObjectSurface,
            _ if p_camera.z < d - GLIMPSE_MARGIN_M - view.depth_noise_m(d) => ViewEvidence::Glimpsed,
            _ => ViewEvidence::Nothing,
        }
    } else {
        match view.states[i] {
            PixelState::ThisObject => ViewEvidence::BehindObject,
            PixelState::OtherObject if p_camera.z <= d + OCCLUDER_DEPTH_M => ViewEvidence::BehindOther,
            PixelState::OtherObject
            | PixelState::Unknown
            | PixelState::Unsure
            | PixelState::HiddenSolid
            | PixelState::BelowSupport
            | PixelState::SeenFree => ViewEvidence::Nothing,
        }
    }
}

/// Whether no pixel of `view`'s crop within [`NO_RETURN_RADIUS_PX`] of `(u, v)` has a depth: a
/// patch the sensor got no return from, which is nothing within its range (or beyond
/// `dataset.max_depth_m`). A depth camera's holes at depth edges and its random dropouts are a
/// pixel or two wide, with valid neighbours.
fn no_depth_around(view: &ObjectView, u: u32, v: u32) -> bool {
    view.nearest_return_around(u, v, NO_RETURN_RADIUS_PX).is_none()
}

/// What all `views` together say of the point: seen free in any view wins, then behind another
/// surface in any (occluded), then at the object's surface in any, then glimpsed in any, then
/// behind the object's surface in any (hidden).
pub fn cell_evidence(views: &[&ObjectView], p_world: &Point3<f32>, margin_m: f32) -> CellEvidence {
    let (mut hidden, mut surface, mut occluded, mut glimpsed) = (false, false, false, false);
    for view in views {
        match view_evidence(view, p_world, margin_m) {
            ViewEvidence::Free => return CellEvidence::SeenFree,
            ViewEvidence::AtObjectSurface => surface = true,
            ViewEvidence::BehindObject => hidden = true,
            ViewEvidence::BehindOther => occluded = true,
            ViewEvidence::Glimpsed => glimpsed = true,
            ViewEvidence::Nothing => {}
        }
    }
    if occluded {
        CellEvidence::Occluded
    } else if surface {
        CellEvidence::Surface
    } else if glimpsed {
        CellEvidence::Glimpsed
    } else if hidden {
        CellEvidence::Hidden
    } else {
        CellEvidence::Unknown
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Isometry3;

    use super::*;
    use crate::ids::FrameIndex;
    use crate::sensor::frame::CameraIntrinsics;
    use crate::sensor::pixel_box::PixelBox;

    /// A 3×3 view from the origin along +z whose every pixel measured the object at `depth_m`.
    fn view(depth_m: f32, depth_noise_per_m2: f32) -> ObjectView {
        ObjectView {
            frame: FrameIndex(0),
            world_from_camera: Isometry3::identity(),
            intrinsics: CameraIntrinsics {
                width: 3,
                height: 3,
                fx: 1.0,
                fy: 1.0,
                cx: 1.0,
                cy: 1.0,
            },
            region: PixelBox {
                u_min: 0,
                v_min: 0,
                u_max: 2,
                v_max: 2,
            },
            rgb: vec![[0; 3]; 9],
            depth_m: vec![depth_m; 9],
            states: vec![PixelState::ThisObject; 9],
            depth_noise_per_m2,
            deepest_return_m: depth_m,
        }
    }

    #[test]
    fn a_noisy_depth_a_few_centimetres_deep_does_not_see_the_objects_inside_free_with_the_allowance() {
        // The allowance a depth camera's settings ship (`dataset.depth_noise_per_m2`).
        let camera = crate::config::MapperConfig::default()
            .with_depth_images(crate::sensor::depth_smoothing::DepthImages::Camera);
        let allowance = camera.dataset.depth_noise_per_m2;
        assert_eq!(allowance, 0.0025);
        // The surface is at 3.00 m; this view measured 3.05 m (noise). A point 2 cm inside.
        let inside = Point3::new(0.0, 0.0, 3.02);
        assert_eq!(
            view_evidence(&view(3.05, 0.0), &inside, 0.01),
            ViewEvidence::Free,
            "exact depth trusted"
        );
        assert_eq!(
            view_evidence(&view(3.05, allowance), &inside, 0.01),
            ViewEvidence::AtObjectSurface,
            "2.3 cm allowed at 3.05 m, and the margin's 1 cm"
        );
        // 4 cm before the measurement is past the allowance and the margin (3.3 cm): seen free,
        // as a table's space under its top is (twice the allowance, 5.7 cm, would not see it).
        let before = Point3::new(0.0, 0.0, 3.01);
        assert_eq!(view_evidence(&view(3.05, allowance), &before, 0.01), ViewEvidence::Free);
        assert_eq!(
            view_evidence(&view(3.05, 2.0 * allowance), &before, 0.01),
            ViewEvidence::AtObjectSurface
        );
        // Space well before the surface is still seen free, and well behind it behind.
        assert_eq!(
            view_evidence(&view(3.05, allowance), &Point3::new(0.0, 0.0, 2.9), 0.01),
            ViewEvidence::Free
        );
        assert_eq!(
            view_evidence(&view(3.05, allowance), &Point3::new(0.0, 0.0, 3.1), 0.01),
            ViewEvidence::BehindObject
        );
    }
}
