//! Per-object keyframe window: which past frames an object's field trains on (vMAP's policy).
//!
//! An object counts the frames it is visible in. Its n-th visible frame (n from 0) is a keyframe
//! when `n % stride == 0`, and the second one always is. The window holds up to `capacity`
//! slots and the newest slot is "live": a frame that is not a keyframe overwrites it, so the
//! mapper always trains on the latest view. A keyframe is appended; once the window is full it
//! is written into the slot chosen for replacement, and a new replacement slot is drawn at random
//! among the slots that are not one of the two newest keyframes. Pure data and policy: the caller
//! passes the random generator.

use rand::{Rng, RngExt};

use crate::ids::FrameIndex;
use crate::objects::config::KeyframeConfig;

/// Which keyframe stride applies: objects and the background differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyframeRole {
    /// A foreground object (`KeyframeConfig::object_stride`).
    Object,
    /// The background (`KeyframeConfig::background_stride`).
    Background,
}

impl KeyframeRole {
    fn stride(self, cfg: &KeyframeConfig) -> u32 {
        match self {
            Self::Object => cfg.object_stride,
            Self::Background => cfg.background_stride,
        }
    }
}

/// What [`KeyframeWindow::offer`] did; callers decide what to log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Admission {
    /// The frame was appended as a new keyframe slot.
    Appended,
    /// The frame overwrote the live slot (a non-keyframe, or a keyframe in a full window);
    /// `replaced` is the frame that slot held.
    Overwrote {
        /// Frame that was dropped from the window.
        replaced: FrameIndex,
        /// Whether the new frame is a keyframe.
        keyframe: bool,
    },
}

impl Admission {
    /// Whether the offered frame became a keyframe (rather than the live slot's newest view).
    pub fn is_keyframe(&self) -> bool {
        matches!(self, Self::Appended | Self::Overwrote { keyframe: true, .. })
    }
}

/// One slot: the frame index and what the caller keeps of that frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct KeyframeSlot<T> {
    /// The frame this slot holds.
    pub frame: FrameIndex,
    /// Caller data (e.g. the shared frame and the object's 2D box in it).
    pub data: T,
}

/// The keyframe window of one object.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct KeyframeWindow<T> {
    slots: Vec<KeyframeSlot<T>>,
    /// Slot overwritten by the next non-keyframe.
    live: usize,
    /// Slots of the two newest keyframes, oldest first.
    recent: Vec<usize>,
    /// Frames this object was visible in so far.
    visible_count: u64,
}

impl<T> Default for KeyframeWindow<T> {
    fn default() -> Self {
        Self {
            slots: Vec::new(),
            live: 0,
            recent: Vec::new(),
            visible_count: 0,
        }
    }
}

impl<T> KeyframeWindow<T> {
    /// Offers the object's next visible frame to the window.
    pub fn offer(
        &mut self,
        frame: FrameIndex,
        data: T,
        role: KeyframeRole,
        cfg: &KeyframeConfig,
        rng: &mut impl Rng,
    ) -> Admission {
        debug_assert!(
            cfg.capacity >= 3,
            "capacity must leave room beside the two recent keyframes"
        );
        let stride = u64::from(role.stride(cfg).max(1));
        let is_keyframe = self.visible_count.is_multiple_of(stride) || self.slots.len() == 1;
        self.visible_count += 1;
        let slot = KeyframeSlot { frame, data };

        if is_keyframe && self.slots.len() < cfg.capacity {
            self.slots.push(slot);
            self.live = self.slots.len() - 1;
            self.mark_recent(self.live);
            return Admission::Appended;
        }
        let replaced = std::mem::replace(&mut self.slots[self.live], slot).frame;
        if is_keyframe {
            self.mark_recent(self.live);
            self.live = self.draw_replaceable_slot(rng);
        }
        Admission::Overwrote {
            replaced,
            keyframe: is_keyframe,
        }
    }

    fn mark_recent(&mut self, slot: usize) {
        self.recent.retain(|&s| s != slot);
        self.recent.push(slot);
        if self.recent.len() > 2 {
            self.recent.remove(0);
        }
    }

    fn draw_replaceable_slot(&self, rng: &mut impl Rng) -> usize {
        let candidates: Vec<usize> = (0..self.slots.len()).filter(|s| !self.recent.contains(s)).collect();
        debug_assert!(!candidates.is_empty(), "capacity >= 3 leaves a non-recent slot");
        candidates[rng.random_range(0..candidates.len())]
    }

    /// Takes in the window of an object found to be part of this one: the slots of both, in
    /// frame order (a frame in both windows keeps this window's slot, with `other`'s data given
    /// to `combine`); beyond `capacity` the two newest are kept and the others thinned evenly.
    /// The two newest become the recent keyframes, and the visible frames add up.
    pub fn absorb(&mut self, other: Self, capacity: usize, rng: &mut impl Rng, combine: impl Fn(&mut T, T)) {
        let mut slots = std::mem::take(&mut self.slots);
        for slot in other.slots {
            match slots.iter_mut().find(|s| s.frame == slot.frame) {
                Some(mine) => combine(&mut mine.data, slot.data),
                None => slots.push(slot),
            }
        }
        slots.sort_by_key(|s| s.frame);
        if slots.len() > capacity.max(3) {
            let (older, newest) = (slots.len() - 2, capacity.max(3) - 2);
            let keep: Vec<usize> = (0..newest).map(|k| k * older / newest).collect();
            let mut i = 0;
            slots.retain(|_| {
                i += 1;
                i > older || keep.contains(&(i - 1))
            });
        }
        let n = slots.len();
        self.slots = slots;
        self.recent = (n.saturating_sub(2)..n).collect();
        self.visible_count += other.visible_count;
        self.live = match n < capacity {
            true => n.saturating_sub(1),
            false => self.draw_replaceable_slot(rng),
        };
    }

    /// Every slot's data, to change in place.
    pub fn data_mut(&mut self) -> impl Iterator<Item = &mut T> {
        self.slots.iter_mut().map(|s| &mut s.data)
    }

    /// All slots, in slot order.
    pub fn slots(&self) -> &[KeyframeSlot<T>] {
        &self.slots
    }

    /// Frame indices held, in slot order.
    pub fn frames(&self) -> Vec<FrameIndex> {
        self.slots.iter().map(|s| s.frame).collect()
    }

    /// The slots of the (up to) two newest keyframes, oldest first; training always uses them.
    pub fn recent_slots(&self) -> &[usize] {
        &self.recent
    }

    /// Frames this object has been visible in.
    pub fn visible_count(&self) -> u64 {
        self.visible_count
    }

    /// Number of slots in use.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// True before the first offer.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn offer_all(window: &mut KeyframeWindow<()>, frames: impl IntoIterator<Item = u64>, cfg: &KeyframeConfig) {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for f in frames {
            window.offer(FrameIndex(f), (), KeyframeRole::Object, cfg, &mut rng);
        }
    }

    #[test]
    fn first_two_frames_are_keyframes_and_later_ones_overwrite_the_live_slot() {
        let cfg = KeyframeConfig {
            capacity: 5,
            object_stride: 4,
            background_stride: 8,
        };
        let mut window = KeyframeWindow::default();
        offer_all(&mut window, 0..4, &cfg);
        assert_eq!(
            window.frames(),
            [0, 3].map(FrameIndex),
            "frames 2 and 3 overwrite slot 1"
        );
        offer_all(&mut window, 4..6, &cfg);
        assert_eq!(
            window.frames(),
            [0, 3, 5].map(FrameIndex),
            "visible frame 4 is a keyframe"
        );
    }

    #[test]
    fn a_full_window_keeps_its_size_and_the_two_newest_keyframes() {
        let cfg = KeyframeConfig {
            capacity: 4,
            object_stride: 2,
            background_stride: 2,
        };
        let mut window = KeyframeWindow::default();
        offer_all(&mut window, 0..40, &cfg);
        assert_eq!(window.len(), 4, "capacity bounds the window");
        let recent: Vec<u64> = window
            .recent_slots()
            .iter()
            .map(|&s| window.slots()[s].frame.0)
            .collect();
        assert_eq!(
            recent,
            [36, 38],
            "the two newest keyframes (every 2nd frame) are remembered as recent"
        );
        assert_eq!(window.visible_count(), 40);
    }

    #[test]
    fn the_background_uses_its_own_stride() {
        let cfg = KeyframeConfig {
            capacity: 10,
            object_stride: 2,
            background_stride: 5,
        };
        let mut window = KeyframeWindow::default();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for f in 0..11 {
            window.offer(FrameIndex(f), (), KeyframeRole::Background, &cfg, &mut rng);
        }
        assert_eq!(window.frames(), [0, 4, 9, 10].map(FrameIndex));
    }

    #[test]
    fn same_seed_same_window() {
        let cfg = KeyframeConfig {
            capacity: 4,
            object_stride: 1,
            background_stride: 1,
        };
        let (mut a, mut b) = (KeyframeWindow::default(), KeyframeWindow::default());
        offer_all(&mut a, 0..50, &cfg);
        offer_all(&mut b, 0..50, &cfg);
        assert_eq!(a.frames(), b.frames());
    }
}
