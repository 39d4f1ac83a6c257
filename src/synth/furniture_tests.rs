//! Tests of the furniture designs.

use super::*;

#[test]
fn designs_have_realistic_sizes_and_stand_on_the_floor() {
    for design in Design::ALL {
        let b = design.mesh().bounds().expect("design has vertices");
        let e = b.extent();
        assert!(
            b.min.z.abs() < 1e-4,
            "{} stands on z = 0, min z = {}",
            design.name(),
            b.min.z
        );
        assert!(
            e.x < 2.1 && e.y < 2.1 && e.z < 1.9,
            "{} fits a room: {e:?}",
            design.name()
        );
        assert!(
            (b.center().x).abs() < 0.02 && (b.center().y).abs() < 0.05,
            "{} is centred",
            design.name()
        );
    }
    let table = Design::DiningTable.mesh().bounds().expect("table");
    assert!((table.max.z - 0.75).abs() < 1e-6, "table is 0.75 m high");
}

#[test]
fn chair_designs_differ_in_shape() {
    let a = Design::LadderBackChair.mesh().bounds().expect("chair A");
    let b = Design::Armchair.mesh().bounds().expect("chair B");
    assert!(a.max.z > b.max.z + 0.05, "the ladder-back is the taller chair");
    assert!(
        b.extent().x > a.extent().x + 0.1,
        "the armchair is wider than the ladder-back"
    );
    assert!(Design::LadderBackChair.is_chair() && Design::Armchair.is_chair());
}

#[test]
fn every_part_is_coloured() {
    for design in Design::ALL {
        for part in design.parts() {
            assert_eq!(part.validate(), Ok(()), "{}", design.name());
            assert!(part.colors.is_some(), "{} parts are painted", design.name());
        }
    }
}
