//! [`RegistrationConfig`]: every constant of METHOD.md §4, with METHOD's values as defaults.

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Where the putative correspondences of the robust back end come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrontEnd {
    /// Correspondence-free TEASER++ ("all-to-all"): every source/template pair of the
    /// downsampled clouds, `max_pairs` of them kept at random.
    AllToAll,
    /// 33-bin FPFH descriptors matched by mutual nearest neighbours in feature space.
    Fpfh,
}

/// Which rotations the registration searches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Rotations {
    /// Every rotation (METHOD.md §4): the 24 cube rotations as starts, ICP in SO(3).
    #[default]
    Any,
    /// Turns about world up only (z): both clouds stand on one floor. Starts every
    /// `twist_deg` about z, ICP solves for the turn about z and a translation. A partly seen
    /// object's cloud tilts under a free rotation (a chair seen at 20 % from behind a table was
    /// registered 4–12° off upright), but that chair completed worse upright on the clean
    /// default scene (1.9–3.0 → 3.5–4.3 cm over three mapper seeds; docs/ROBUSTNESS.md): not the
    /// default.
    AboutUp,
}

/// What becomes of the small tilt a search over [`Rotations::Any`] may find.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Tilt {
    /// Kept as searched (METHOD.md §4).
    Kept,
    /// A found rotation whose tilt lies within `removed_tilt_deg` is turned to the nearest turn
    /// about world up and refined over turns about up (the search stays over every rotation): both clouds
    /// stand on one floor. Under a Kinect-like camera and a segmenter's masks the chair seen at
    /// 20 % under a table was registered 4.4–4.8° off, almost all of it a tilt.
    #[default]
    Removed,
}

/// Registration of a partially observed object to its category representative (METHOD.md §4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RegistrationConfig {
    /// Which rotations are searched: `"any"` (METHOD.md §4, the default) or `"about_up"`.
    pub rotations: Rotations,
    /// With `rotations = "any"`: `"removed"` (the found rotation's small tilt is removed, the
    /// default) or `"kept"` (METHOD.md §4).
    pub tilt: Tilt,
    /// Tilts (angle between world up and the found rotation's image of it, degrees) that
    /// `tilt = "removed"` removes: from the first to the second. A smaller one is within the
    /// search's precision and kept as found (its refinement about up would only move the
    /// translation); a larger one is an object on its side.
    pub removed_tilt_deg: [f32; 2],
    /// Correspondence front end.
    pub front_end: FrontEnd,
    /// Edge of the voxel grid both clouds are thinned on (one centroid per voxel) before the
    /// front end, metres.
    pub voxel_m: f32,
    /// All-to-all front end: most source/template pairs kept (drawn at random, seeded).
    pub max_pairs: usize,
    /// Bound on the position error of one matched point, metres. Two correspondences are
    /// consistent when their pairwise lengths differ by at most twice this.
    pub noise_bound_m: f32,
    /// Branch-and-bound nodes the exact maximum clique search may expand. When it runs out, the
    /// largest clique found so far is used (at least the greedy degeneracy-ordered clique).
    pub max_clique_nodes: u64,
    /// GNC-TLS rotation: factor the control parameter μ grows by per iteration.
    pub gnc_factor: f64,
    /// GNC-TLS rotation: most iterations (one weighted Horn/SVD solve each).
    pub gnc_max_iterations: usize,
    /// GNC-TLS rotation: stop when the weighted cost changes by less than this (dimensionless).
    pub gnc_cost_threshold: f64,
    /// Edge of the voxel grid of the clouds ICP refines on, metres.
    pub icp_voxel_m: f32,
    /// ICP: farthest a nearest neighbour may be to count as a correspondence, metres.
    pub icp_max_correspondence_m: f32,
    /// ICP: most iterations.
    pub icp_max_iterations: usize,
    /// Every ICP run (search, refinement and plain) stops at a step that turns by less than this
    /// many radians and moves by less than this many metres.
    pub icp_step_tolerance: f64,
    /// Seed one extra candidate with the front end + TEASER++ back end estimate (computed once:
    /// with all-to-all pairs it does not depend on the initial rotation).
    pub robust_start: bool,
    /// Edge of the voxel grid of the clouds every start is first refined on, metres.
    pub search_voxel_m: f32,
    /// Trimmed-ICP gates of the coarse stages every start runs, metres (one stage per gate).
    pub search_gates_m: Vec<f32>,
    /// Most iterations of each coarse stage.
    pub search_iterations: usize,
    /// Most coarse source points (an even stride subset) the coarse stages run on; the coarse
    /// ranking after them scores the whole coarse source. 400 halves the time of a pair against
    /// the whole source (~1 000–2 000 points) and keeps 80/80 of `bench_registration`'s trials.
    pub search_points: usize,
    /// Trimmed ICP and the coarse ranking of starts: fraction of the closest pairs kept.
    pub keep_fraction: f32,
    /// Candidates (best coarse scores, one per distinct pose) refined on the fine clouds; the one
    /// with the smallest whole (untrimmed) one-way Chamfer distance wins, as in the reference.
    pub refined_candidates: usize,
    /// Trimmed-ICP gates of the fine stages, metres, before the final plain ICP.
    pub refine_gates_m: Vec<f32>,
    /// Most iterations of each fine stage.
    pub refine_iterations: usize,
    /// Extra starts per cube rotation: the cube rotation composed with a turn of
    /// `twist_deg` about ±x, ±y, ±z (0 or 6).
    pub twists: usize,
    /// Angle of the twists, degrees.
    pub twist_deg: f32,
    /// Source points (a stride subset of the coarse source) that rank the starts.
    pub ranking_points: usize,
    /// Translation-only trimmed ICP steps every start takes before it is ranked.
    pub translation_iterations: usize,
    /// Best-ranked starts that run the coarse trimmed ICP.
    pub ranked_starts: usize,
    /// FPFH: radius of the PCA neighbourhood of a normal, in voxels (`voxel_m`).
    pub fpfh_normal_radius_voxels: f32,
    /// FPFH: radius of the descriptor's neighbourhood, in voxels (`voxel_m`).
    pub fpfh_feature_radius_voxels: f32,
}

impl RegistrationConfig {
    /// Whether a found `rotation` has its tilt removed ([`Tilt::Removed`]): rotations searched
    /// freely, and world up turned by an angle within `removed_tilt_deg`.
    pub fn removes_tilt(&self, rotation: &UnitQuaternion<f64>) -> bool {
        let up = rotation * Vector3::z();
        let tilt_deg = up.z.clamp(-1.0, 1.0).acos().to_degrees();
        let [least, most] = self.removed_tilt_deg.map(f64::from);
        self.rotations == Rotations::Any && self.tilt == Tilt::Removed && (least..=most).contains(&tilt_deg)
    }
}

impl Default for RegistrationConfig {
    fn default() -> Self {
        Self {
            rotations: Rotations::Any,
            tilt: Tilt::Removed,
            removed_tilt_deg: [1.0, 15.0],
            front_end: FrontEnd::AllToAll,
            voxel_m: 0.1,
            max_pairs: 10_000,
            noise_bound_m: 0.01,
            max_clique_nodes: 200_000,
            gnc_factor: 1.4,
            gnc_max_iterations: 100,
            gnc_cost_threshold: 1e-6,
            icp_voxel_m: 0.02,
            icp_max_correspondence_m: 0.01,
            icp_max_iterations: 100,
            icp_step_tolerance: 1e-5,
            robust_start: false,
            search_voxel_m: 0.05,
            search_gates_m: vec![0.3, 0.1],
            search_iterations: 20,
            search_points: 400,
            keep_fraction: 0.8,
            refined_candidates: 3,
            refine_gates_m: vec![0.05, 0.025],
            refine_iterations: 30,
            twists: 6,
            twist_deg: 30.0,
            ranking_points: 64,
            ranked_starts: 48,
            translation_iterations: 5,
            fpfh_normal_radius_voxels: 2.0,
            fpfh_feature_radius_voxels: 5.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tilted(deg: f64) -> UnitQuaternion<f64> {
        UnitQuaternion::from_euler_angles(deg.to_radians(), 0.0, 0.7)
    }

    #[test]
    fn only_a_tilt_of_one_to_fifteen_degrees_of_a_free_search_is_removed() {
        let cfg = RegistrationConfig::default();
        assert!(!cfg.removes_tilt(&tilted(0.0)), "a turn about up has none");
        assert!(!cfg.removes_tilt(&tilted(0.5)), "within the search's precision");
        assert!(cfg.removes_tilt(&tilted(4.5)) && cfg.removes_tilt(&tilted(-14.0)));
        assert!(!cfg.removes_tilt(&tilted(40.0)), "an object on its side");
        let kept = RegistrationConfig {
            tilt: Tilt::Kept,
            ..RegistrationConfig::default()
        };
        assert!(!kept.removes_tilt(&tilted(4.5)));
        let upright = RegistrationConfig {
            rotations: Rotations::AboutUp,
            ..RegistrationConfig::default()
        };
        assert!(
            !upright.removes_tilt(&tilted(4.5)),
            "an upright search has nothing to remove"
        );
    }

    #[test]
    fn a_config_file_may_list_only_overrides() {
        let cfg: RegistrationConfig = toml::from_str("front_end = \"fpfh\"\nvoxel_m = 0.05").expect("valid TOML");
        let expected = RegistrationConfig {
            front_end: FrontEnd::Fpfh,
            voxel_m: 0.05,
            ..RegistrationConfig::default()
        };
        assert_eq!(cfg, expected);
    }

    #[test]
    fn unknown_keys_are_rejected() {
        assert!(toml::from_str::<RegistrationConfig>("voxel = 0.05").is_err());
    }
}
