//! Tests of [`super`]: codes, remaps, one shape per subcategory, evaluation.

use super::*;
use crate::rng::{RngStream, seeded_rng};

#[test]
fn remapping_members_moves_codes_and_keeps_the_network() {
    let mut rng = seeded_rng(2, RngStream::Mapper);
    let mut field = CategoryField::new(32, 8, 1.0, 3, &mut rng);
    let before = field.clone();
    field.remap_members(&[Some(2), None, Some(0)], &mut rng).expect("valid");
    assert_eq!(field.num_members(), 3);
    assert_eq!(field.code(0), before.code(2));
    assert_eq!(field.code(2), before.code(0));
    assert_ne!(field.code(1), before.code(1), "a fresh code");
    assert_eq!(field.params(), before.params());
    assert!(field.remap_members(&[Some(5)], &mut rng).is_err());
}

#[test]
fn codes_start_with_codenerfs_spread_and_are_seeded() {
    let field = CategoryField::new(32, 64, 1.0, 40, &mut seeded_rng(1, RngStream::Mapper));
    let again = CategoryField::new(32, 64, 1.0, 40, &mut seeded_rng(1, RngStream::Mapper));
    assert_eq!(field, again, "same seed, same weights and codes");
    let codes: Vec<f32> = field.codes().concat();
    let var = codes.iter().map(|v| f64::from(*v).powi(2)).sum::<f64>() / codes.len() as f64;
    assert!((var / (2.0 / 64.0) - 1.0).abs() < 0.1, "variance {var} vs 2/D");
    assert_eq!((field.param_count(), field.code_param_count()), (22_275, 128));
}

#[test]
fn a_field_with_one_shape_keeps_every_members_shape_code_zero_and_its_texture_code() {
    let mut rng = seeded_rng(2, RngStream::Mapper);
    let own = CategoryField::new(32, 8, 1.0, 2, &mut rng);
    let mut shared = own.clone().with_shape_codes(ShapeCodes::Shared);
    for member in 0..2 {
        assert_eq!(shared.shape_code(member), Some(&[0.0; 8][..]), "member {member}");
        assert_eq!(shared.texture_code(member), own.texture_code(member));
    }
    assert_ne!(own.shape_code(0), Some(&[0.0; 8][..]), "own shapes are drawn");
    let added = shared.add_member(&mut rng);
    shared
        .remap_members(&[Some(added), None, Some(0)], &mut rng)
        .expect("valid");
    for member in 0..3 {
        assert_eq!(
            shared.shape_code(member),
            Some(&[0.0; 8][..]),
            "member {member} after a remap"
        );
        assert!(shared.texture_code(member).unwrap().iter().any(|&z| z != 0.0));
    }
}

#[test]
fn evaluating_an_unknown_member_is_an_error() {
    let field = CategoryField::new(32, 8, 1.0, 2, &mut seeded_rng(2, RngStream::Mapper));
    let points = [[0.1, 0.2, 0.3], [-0.4, 0.0, 0.5]];
    assert!(field.eval_occupancy(2, &points).is_err(), "member 2 of 2");
    let eval = field.eval(1, &points).expect("member 1 exists");
    assert_eq!((eval.occupancy.len(), eval.colour.len()), (2, 2));
    let occupancy = field.eval_occupancy(1, &points).expect("member 1 exists");
    assert_eq!(occupancy, eval.occupancy, "both heads give the same occupancy");
}
