//! The 24 rotations of the cube: the initial orientations tried by
//! [`register_to_representative`](super::register_to_representative).
//!
//! Each rotation maps the x axis to a signed coordinate axis s_x·e_i and the y axis to another,
//! s_y·e_j (i ≠ j): 6 ordered axis pairs × 4 sign choices. The z axis follows as z = x × y, so
//! every matrix R = [x y z] is proper (det R = +1).

use nalgebra::{Matrix3, Rotation3, Vector3};

/// The 24 proper rotations of the cube, in a fixed order (axis pair major, then signs).
pub fn cube_rotations() -> [Rotation3<f32>; 24] {
    let mut rotations = [Rotation3::identity(); 24];
    let mut k = 0;
    for i in 0..3 {
        for j in (0..3).filter(|&j| j != i) {
            for (sx, sy) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                let x: Vector3<f32> = Vector3::ith(i, sx);
                let y: Vector3<f32> = Vector3::ith(j, sy);
                let z = x.cross(&y);
                rotations[k] = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
                k += 1;
            }
        }
    }
    debug_assert_eq!(k, 24, "6 axis pairs × 4 sign flips");
    rotations
}

#[cfg(test)]
mod tests {
    use super::*;

    fn index_of(rotations: &[Rotation3<f32>], r: &Rotation3<f32>) -> Option<usize> {
        rotations
            .iter()
            .position(|q| (q.matrix() - r.matrix()).abs().max() < 1e-6)
    }

    #[test]
    fn the_24_rotations_are_distinct_and_proper() {
        let rotations = cube_rotations();
        for (a, r) in rotations.iter().enumerate() {
            assert!((r.matrix().determinant() - 1.0).abs() < 1e-6, "rotation {a} has det +1");
            let orthogonality = (r.matrix().transpose() * r.matrix() - Matrix3::identity()).abs().max();
            assert!(orthogonality < 1e-6, "rotation {a} is orthogonal");
            assert_eq!(index_of(&rotations, r), Some(a), "rotation {a} appears once");
        }
    }

    #[test]
    fn the_24_rotations_form_a_group() {
        let rotations = cube_rotations();
        assert!(
            index_of(&rotations, &Rotation3::identity()).is_some(),
            "identity is included"
        );
        for a in &rotations {
            assert!(index_of(&rotations, &a.inverse()).is_some(), "closed under inverses");
            for b in &rotations {
                assert!(index_of(&rotations, &(a * b)).is_some(), "closed under composition");
            }
        }
    }
}
