//! Pipeline tests of the synthetic scene generator: determinism, ground-truth consistency, partial
//! observation, and the Replica vMAP layout it writes.

use std::collections::BTreeSet;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use catmap::dataset::FrameSource;
use catmap::geometry::mesh::TriangleMesh;
use catmap::synth::{Design, Preset, SceneDescription, SyntheticScene, write_replica_layout};
use catmap::{InstanceLabel, ObjectId};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn small_scene(seed: u64) -> SyntheticScene {
    SyntheticScene::generate(seed, Preset::Small).expect("the small preset always fits its room")
}

#[test]
fn the_same_seed_gives_identical_frames_and_descriptions() {
    let (a, b) = (small_scene(7), small_scene(7));
    assert_eq!(
        SceneDescription::of(&a),
        SceneDescription::of(&b),
        "same seed, same scene.json"
    );
    for i in 0..a.len() {
        assert_eq!(
            a.render(i).expect("frame"),
            b.render(i).expect("frame"),
            "frame {i} renders identically"
        );
    }
}

#[test]
fn different_seeds_give_different_layouts() {
    let (a, b) = (small_scene(1), small_scene(2));
    let poses = |s: &SyntheticScene| s.objects().iter().map(|o| o.world_from_object).collect::<Vec<_>>();
    assert_ne!(poses(&a), poses(&b), "seeds 1 and 2 place the furniture differently");
}

#[test]
fn the_small_preset_has_three_identical_chairs_at_different_poses() {
    let scene = small_scene(3);
    let chairs: Vec<_> = scene
        .objects()
        .iter()
        .filter(|o| o.design == Design::LadderBackChair)
        .collect();
    assert!(
        chairs.len() >= 3,
        "at least three chairs of one design, got {}",
        chairs.len()
    );
    let reference = Design::LadderBackChair.mesh();
    for chair in &chairs {
        let in_object = chair.mesh_in_world.transformed(&chair.world_from_object.inverse());
        assert_eq!(
            in_object.triangles, reference.triangles,
            "chair {} has the design's topology",
            chair.id
        );
        let max_error = in_object
            .vertices
            .iter()
            .zip(&reference.vertices)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f32::max);
        assert!(
            max_error < 1e-5,
            "chair {} is the design moved rigidly (error {max_error} m)",
            chair.id
        );
    }
    let distinct: BTreeSet<_> = chairs
        .iter()
        .map(|c| c.world_from_object.translation.vector.map(|x| x.to_bits()).data.0)
        .collect();
    assert_eq!(distinct.len(), chairs.len(), "chairs stand in different places");
}

#[test]
fn object_depth_back_projects_onto_its_ground_truth_mesh() {
    let scene = small_scene(4);
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let trees: Vec<(ObjectId, ImmutableKdTree<f32, 3>)> = scene
        .objects()
        .iter()
        .map(|o| {
            let samples = o
                .surface_in_world
                .sample_surface(200_000, &mut rng)
                .expect("objects have area");
            let points: Vec<[f32; 3]> = samples.iter().map(|p| [p.x, p.y, p.z]).collect();
            (
                o.id,
                ImmutableKdTree::new_from_slice(&points).expect("kd-tree over surface samples"),
            )
        })
        .collect();
    let mut checked = 0;
    for position in [0, 10, 20, 29] {
        let frame = scene.read_frame(position).expect("frame");
        for i in 0..frame.instances.len() {
            let InstanceLabel::Object(id) = frame.instances.label(i) else {
                continue;
            };
            let (_, tree) = trees.iter().find(|(o, _)| *o == id).expect("labels name scene objects");
            let p = frame.point_in_world(i).expect("object pixels have depth");
            let nearest = tree
                .query(&[p.x, p.y, p.z])
                .nearest_one::<SquaredEuclidean<f32>>()
                .execute();
            let distance = nearest.distance.sqrt();
            assert!(
                distance < 0.01,
                "frame {position} pixel {i} of object {id} lies {distance} m off its mesh"
            );
            checked += 1;
        }
    }
    assert!(checked > 1000, "the test checks many object pixels, got {checked}");
}

#[test]
fn every_object_is_visible_in_some_frame() {
    let scene = small_scene(5);
    let mut seen = BTreeSet::new();
    for position in 0..scene.len() {
        let frame = scene.read_frame(position).expect("frame");
        seen.extend((0..frame.instances.len()).filter_map(|i| frame.instances.object_at(i)));
    }
    let all: BTreeSet<ObjectId> = scene.objects().iter().map(|o| o.id).collect();
    assert_eq!(seen, all, "every object appears in at least one frame");
}

#[test]
fn objects_are_only_partly_observed() {
    for (preset, seed) in [(Preset::Small, 6), (Preset::Default, 6), (Preset::Living, 6)] {
        let scene = SyntheticScene::generate(seed, preset).expect("scene");
        let fractions = scene.observed_surface_fraction();
        assert_eq!(fractions.len(), scene.objects().len());
        for (id, &f) in fractions {
            assert!(
                f > 0.0 && f < 1.0,
                "{preset}: object {id} observed fraction {f} lies in (0, 1)"
            );
        }
        let mostly_hidden = fractions.values().filter(|&&f| f < 0.9).count();
        assert!(
            2 * mostly_hidden > fractions.len(),
            "{preset}: most objects keep unseen surface: {fractions:?}"
        );
    }
}

#[test]
fn the_written_layout_matches_the_replica_vmap_format() {
    let scene = small_scene(8);
    let dir = tempfile::tempdir().expect("temp dir");
    let calls = AtomicUsize::new(0);
    write_replica_layout(&scene, dir.path(), |_, total| {
        assert_eq!(total, scene.len());
        calls.fetch_add(1, Ordering::Relaxed);
    })
    .expect("write layout");
    assert_eq!(calls.into_inner(), scene.len(), "progress is reported once per frame");

    let k = scene.intrinsics();
    let expected = [
        ("rgb", "rgb", image::ColorType::Rgb8),
        ("depth", "depth", image::ColorType::L16),
        ("semantic_class", "semantic_class", image::ColorType::L8),
        ("semantic_instance", "semantic_instance", image::ColorType::L16),
    ];
    for (folder, stem, color) in expected {
        assert_eq!(
            std::fs::read_dir(dir.path().join(folder)).expect("folder").count(),
            scene.len(),
            "{folder}"
        );
        for i in 0..scene.len() {
            let img = image::open(dir.path().join(format!("{folder}/{stem}_{i}.png"))).expect("readable PNG");
            assert_eq!(
                (img.width(), img.height(), img.color()),
                (k.width, k.height, color),
                "{folder} frame {i}"
            );
        }
    }
    let depth = image::open(dir.path().join("depth/depth_12.png"))
        .expect("depth")
        .into_luma16();
    let frame = scene.read_frame(12).expect("frame");
    for (mm, &m) in depth.as_raw().iter().zip(&frame.depth_m) {
        assert!(
            (f32::from(*mm) / 1000.0 - m).abs() <= 0.0006,
            "depth PNG holds millimetres"
        );
    }

    let traj = std::fs::read_to_string(dir.path().join("traj_w_c.txt")).expect("trajectory");
    assert_eq!(traj.lines().count(), scene.len(), "one pose per frame");
    for (line, pose) in traj.lines().zip(scene.trajectory()) {
        let values: Vec<f32> = line.split_whitespace().map(|v| v.parse().expect("float")).collect();
        let m = pose.to_homogeneous();
        assert_eq!(values.len(), 16);
        assert!(
            (0..16).all(|k| (values[k] - m[(k / 4, k % 4)]).abs() < 1e-6),
            "row-major camera-to-world"
        );
    }

    let intrinsics: serde_json::Value = read_json(&dir.path().join("intrinsics.json"));
    assert_eq!(intrinsics["width"], k.width);
    assert_eq!(intrinsics["depth_scale"], 1000.0);
    let description: SceneDescription =
        serde_json::from_value(read_json(&dir.path().join("scene.json"))).expect("scene.json");
    assert_eq!(description, SceneDescription::of(&scene));
    for object in scene.objects() {
        let mesh =
            TriangleMesh::read_ply(&dir.path().join(format!("gt_meshes/obj_{}.ply", object.id))).expect("GT mesh");
        assert_eq!(
            mesh, object.surface_in_world,
            "GT mesh of object {} round-trips",
            object.id
        );
    }
    let leftovers = walk(dir.path())
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "tmp"))
        .count();
    assert_eq!(leftovers, 0, "no temporary files remain");
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("json file")).expect("valid json")
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let entries = std::fs::read_dir(dir)
        .expect("folder")
        .map(|e| e.expect("entry").path());
    entries
        .flat_map(|p| if p.is_dir() { walk(&p) } else { vec![p] })
        .collect()
}
