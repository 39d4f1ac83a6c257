//! `categories.json`: per class, its subcategories with representative, members, each member's
//! Chamfer scores and Sim(3) `world_from_nocs` (4×4, row-major; the unit cube → the object's box).

use std::path::Path;

use bevy_ecs::prelude::*;
use catmap::{ClassId, ObjectId};
use serde::Serialize;

use std::collections::BTreeMap;

use crate::components::{Category, Object, Reliability, Subcategories};

/// One member of a subcategory.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MemberRecord {
    /// The object.
    pub id: ObjectId,
    /// Normalised one-way Chamfer distance to the representative (0 for the representative).
    pub chamfer: f32,
    /// The reverse distance, only when the subcategory rule needed it (a Chamfer distance
    /// between `categories.subcategories.same_below` and `new_above`); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reverse_chamfer: Option<f32>,
    /// Sim(3) from NOCS (the unit cube) to the object's box in world coordinates, row-major 4×4.
    pub world_from_nocs: [[f32; 4]; 4],
    /// Box edge lengths, metres.
    pub extents: [f32; 3],
    /// Reliable rays of its uncertainty sphere (what ranks the representative); absent for a
    /// class of one member (nothing to rank, so no sphere is evaluated).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reliable_rays: Option<usize>,
}

/// One subcategory.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SubcategoryRecord {
    /// The representative.
    pub representative: ObjectId,
    /// Its members, by id.
    pub members: Vec<MemberRecord>,
}

/// One class.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClassRecord {
    /// The class.
    pub class: ClassId,
    /// Its class name when known.
    pub name: Option<String>,
    /// Its subcategories (empty until the class was registered).
    pub subcategories: Vec<SubcategoryRecord>,
}

/// Every class's subcategories, sorted by class.
pub fn category_records(world: &mut World) -> Vec<ClassRecord> {
    let names = world.resource::<crate::resources::DatasetClasses>().0.clone();
    let reliable: BTreeMap<ObjectId, usize> = world
        .query::<(&Object, &Reliability)>()
        .iter(world)
        .map(|(o, r)| (o.id, r.0.sphere.reliable_rays))
        .collect();
    let mut records: Vec<ClassRecord> = world
        .query::<(&Category, Option<&Subcategories>)>()
        .iter(world)
        .map(|(category, subcategories)| ClassRecord {
            class: category.class,
            name: names.get(category.class).map(str::to_owned),
            subcategories: subcategories.map_or_else(Vec::new, |s| {
                s.groups
                    .iter()
                    .map(|g| SubcategoryRecord {
                        representative: g.representative,
                        members: g
                            .members
                            .iter()
                            .map(|(id, m)| {
                                let h = m.nocs.world_from_nocs.to_homogeneous();
                                MemberRecord {
                                    id: *id,
                                    chamfer: m.alignment.chamfer,
                                    reverse_chamfer: m.alignment.reverse_chamfer,
                                    world_from_nocs: std::array::from_fn(|r| std::array::from_fn(|c| h[(r, c)])),
                                    extents: m.nocs.extents.into(),
                                    reliable_rays: reliable.get(id).copied(),
                                }
                            })
                            .collect(),
                    })
                    .collect()
            }),
        })
        .collect();
    records.sort_by_key(|r| r.class);
    records
}

/// Writes `records` as pretty JSON, atomically.
pub fn write_category_records(records: &[ClassRecord], path: &Path) -> catmap::Result<()> {
    let mut text = serde_json::to_string_pretty(records).expect("records hold only JSON-representable fields");
    text.push('\n');
    catmap::atomic_file::write_atomic(path, text.as_bytes())
}
