//! What the mapper tells the [`super::StepScheduler`] about each field: which field it is
//! ([`FieldKey`]), what it is for ([`FieldRole`]), what this tick's frames showed of it
//! ([`Sighting`]) and whether frames still stream in ([`StreamPhase`]).

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::ids::{FrameIndex, ObjectId};

/// A field the scheduler plans for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum FieldKey {
    /// An object's own occupancy field.
    Object(ObjectId),
    /// A category field, by its creation number (stable while its membership changes).
    Category(u32),
    /// The background field.
    Background,
}

/// What a field is for at the moment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FieldRole {
    /// Its own mesh comes from it: it trains while it gains from steps.
    Learning,
    /// A category member's own field while the stream lasts: the category field makes the mesh;
    /// it trains only on a new keyframe (uncertainty and re-registration read it).
    Supporting,
    /// It gets no steps.
    Frozen,
}

/// What this tick's frames showed of a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Sighting {
    /// Not in this tick's frames.
    Unseen,
    /// In a frame of this tick (its live keyframe slot changed).
    Seen,
    /// In a frame of this tick that became one of its keyframes.
    NewKeyframe,
}

impl Sighting {
    /// What the frames of this tick (`this_tick`) showed of an object last seen in frame
    /// `last.frame` (`last.keyframe`: that frame became one of its keyframes).
    pub fn of(last: Option<LastSeen>, this_tick: &[FrameIndex]) -> Self {
        match last {
            Some(seen) if this_tick.contains(&seen.frame) => {
                if seen.keyframe {
                    Self::NewKeyframe
                } else {
                    Self::Seen
                }
            }
            _ => Self::Unseen,
        }
    }

    /// The strongest of two sightings (a category field is seen when any member is).
    pub fn max(self, other: Self) -> Self {
        let rank = |s: Self| match s {
            Self::Unseen => 0,
            Self::Seen => 1,
            Self::NewKeyframe => 2,
        };
        if rank(other) > rank(self) { other } else { self }
    }
}

/// The latest frame an object was seen in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct LastSeen {
    /// The frame.
    pub frame: FrameIndex,
    /// Whether it became one of the object's keyframes.
    pub keyframe: bool,
}

/// Whose mesh an object's own field makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshSource {
    /// Its own field.
    OwnField,
    /// Its category field (it is a member of one).
    CategoryField,
}

impl MeshSource {
    /// Where the mesh of an object comes from, by whether it is a category field's member.
    pub fn of_category_member(is_member: bool) -> Self {
        if is_member { Self::CategoryField } else { Self::OwnField }
    }
}

/// Whether other objects share a field's class.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ClassShare {
    /// An object alone in its class: nothing completes it but its own field and the priors,
    /// and it trains at least `schedule.plateau.min_steps_alone` steps.
    Alone,
    /// Objects with twins, and category fields.
    Shared,
}

impl ClassShare {
    /// The share of an object whose class holds `class_size` objects, itself included (see
    /// [`takes_shape_priors`]).
    pub fn of_class_size(class_size: usize) -> Self {
        if takes_shape_priors(class_size) {
            Self::Alone
        } else {
            Self::Shared
        }
    }
}

/// Whether an object's field takes the priors of objects without a twin (the solid prior,
/// `objects::hidden_space`): only when no other object shares its class (`class_size`: the
/// objects of its class, itself included). Objects with twins are completed from them by a
/// category field, and their own fields, which registration and the uncertainty ranking read,
/// stay the observations' alone.
pub fn takes_shape_priors(class_size: usize) -> bool {
    class_size <= 1
}

/// Per object, the number of objects of its class.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClassSizes(HashMap<ObjectId, usize>);

impl ClassSizes {
    /// The objects of `id`'s class, itself included; 1 for an object in no class (alone).
    pub fn of(&self, id: ObjectId) -> usize {
        self.0.get(&id).copied().unwrap_or(1)
    }
}

/// Per object, the number of objects of its class, from each class's member list.
pub fn class_sizes<'a>(classes: impl IntoIterator<Item = &'a [ObjectId]>) -> ClassSizes {
    ClassSizes(
        classes
            .into_iter()
            .flat_map(|members| members.iter().map(move |id| (*id, members.len())))
            .collect(),
    )
}

/// Whether frames are still streaming in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamPhase {
    /// Frames arrive.
    Streaming,
    /// The stream has ended.
    Ended,
}

impl FieldRole {
    /// The role of an object's own field: learning while it makes the object's mesh; once a
    /// category field makes it, supporting while the stream lasts (uncertainty and
    /// re-registration read it) and frozen after.
    pub fn of_object_field(mesh: MeshSource, phase: StreamPhase) -> Self {
        match (mesh, phase) {
            (MeshSource::OwnField, _) => Self::Learning,
            (MeshSource::CategoryField, StreamPhase::Streaming) => Self::Supporting,
            (MeshSource::CategoryField, StreamPhase::Ended) => Self::Frozen,
        }
    }
}

/// The facts about one field that a plan depends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldFacts {
    /// Which field.
    pub key: FieldKey,
    /// What it is for.
    pub role: FieldRole,
    /// What this tick's frames showed of it.
    pub sighting: Sighting,
    /// Whether frames still stream in.
    pub phase: StreamPhase,
    /// Whether other objects share its class.
    pub class: ClassShare,
}

/// The facts of object `id`'s own field.
pub fn object_field_facts(
    id: ObjectId,
    last_seen: Option<LastSeen>,
    mesh: MeshSource,
    phase: StreamPhase,
    this_tick: &[FrameIndex],
    class: ClassShare,
) -> FieldFacts {
    FieldFacts {
        key: FieldKey::Object(id),
        role: FieldRole::of_object_field(mesh, phase),
        sighting: Sighting::of(last_seen, this_tick),
        phase,
        class,
    }
}

/// The facts of category field `id` (its creation number): always learning, seen as its most
/// recently seen member.
pub fn category_field_facts(
    id: u32,
    members_last_seen: impl IntoIterator<Item = Option<LastSeen>>,
    phase: StreamPhase,
    this_tick: &[FrameIndex],
) -> FieldFacts {
    let sighting = members_last_seen
        .into_iter()
        .map(|last| Sighting::of(last, this_tick))
        .fold(Sighting::Unseen, Sighting::max);
    FieldFacts {
        key: FieldKey::Category(id),
        role: FieldRole::Learning,
        sighting,
        phase,
        class: ClassShare::Shared,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn only_objects_alone_in_their_class_take_the_shape_priors() {
        assert!(super::takes_shape_priors(1));
        assert!(!super::takes_shape_priors(2) && !super::takes_shape_priors(7));
        let (chairs, lamp) = ([ObjectId(1), ObjectId(4)], [ObjectId(2)]);
        let sizes = super::class_sizes([&chairs[..], &lamp[..]]);
        assert_eq!(
            (sizes.of(ObjectId(1)), sizes.of(ObjectId(4)), sizes.of(ObjectId(2))),
            (2, 2, 1)
        );
        assert_eq!(sizes.of(ObjectId(9)), 1, "an object in no class is alone");
    }

    use super::*;

    #[test]
    fn sightings_come_from_the_latest_frame_an_object_was_seen_in() {
        let tick = [FrameIndex(7), FrameIndex(8)];
        let seen = |frame, keyframe| {
            Some(LastSeen {
                frame: FrameIndex(frame),
                keyframe,
            })
        };
        assert_eq!(Sighting::of(seen(8, false), &tick), Sighting::Seen);
        assert_eq!(Sighting::of(seen(7, true), &tick), Sighting::NewKeyframe);
        assert_eq!(
            Sighting::of(seen(6, true), &tick),
            Sighting::Unseen,
            "seen in an earlier tick"
        );
        assert_eq!(Sighting::of(None, &tick), Sighting::Unseen);
        assert_eq!(Sighting::Seen.max(Sighting::NewKeyframe), Sighting::NewKeyframe);
        assert_eq!(Sighting::Seen.max(Sighting::Unseen), Sighting::Seen);
    }

    #[test]
    fn a_category_member_supports_while_streaming_and_freezes_after() {
        use FieldRole::*;
        let role = FieldRole::of_object_field;
        assert_eq!(role(MeshSource::OwnField, StreamPhase::Streaming), Learning);
        assert_eq!(role(MeshSource::OwnField, StreamPhase::Ended), Learning);
        assert_eq!(role(MeshSource::CategoryField, StreamPhase::Streaming), Supporting);
        assert_eq!(role(MeshSource::CategoryField, StreamPhase::Ended), Frozen);
    }

    #[test]
    fn a_category_field_is_seen_when_any_member_is() {
        let tick = [FrameIndex(5)];
        let seen = |frame, keyframe| {
            Some(LastSeen {
                frame: FrameIndex(frame),
                keyframe,
            })
        };
        let facts = category_field_facts(2, [seen(3, true), seen(5, false), None], StreamPhase::Streaming, &tick);
        assert_eq!(
            facts,
            FieldFacts {
                key: FieldKey::Category(2),
                role: FieldRole::Learning,
                sighting: Sighting::Seen,
                phase: StreamPhase::Streaming,
                class: ClassShare::Shared,
            }
        );
        let facts = object_field_facts(
            ObjectId(4),
            seen(5, true),
            MeshSource::CategoryField,
            StreamPhase::Streaming,
            &tick,
            ClassShare::Shared,
        );
        assert_eq!(
            (facts.role, facts.sighting),
            (FieldRole::Supporting, Sighting::NewKeyframe)
        );
    }
}
