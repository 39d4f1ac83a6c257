//! The rules that pick which cells of an object's box the priors draw from
//! ([`super::hidden_space`]): which hidden cells the solid prior takes, whether cells no view saw
//! count as hidden, and which cells the seen-free prior takes.

/// Which hidden cells the solid prior asks to be solid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HiddenCells {
    /// Every hidden cell.
    All,
    /// Hidden cells enclosed sideways: walking from the cell along box x or y (both ways)
    /// through hidden cells, no walk ends at a cell seen free or occluded. Space under a
    /// tabletop opens sideways onto space seen between its legs or hidden by the chairs under
    /// it; the inside of a carcass seen from behind ends at its observed panels or at the
    /// box's faces.
    #[default]
    Enclosed,
}

/// Which cells the seen-free prior asks to be empty.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FreeCells {
    /// The cells a view saw free.
    Seen,
    /// Those, and the hidden cells open sideways onto space a view saw through under the object
    /// (a walk along box x or y through hidden cells ends at a cell seen free or glimpsed with
    /// the object above it: its observed surface, or space hidden behind it).
    SeenAndOpen,
    /// Those, and the cells of the ring one cell thick around the box's sides and top that no
    /// view saw free and none saw at the object's surface or behind another object — hidden
    /// behind the object, or glimpsed — and whose mirror image (with a plane) is not in the box:
    /// the region the object is meshed in reaches 0.9 cell past the box, and a field left to
    /// itself fills it behind a sofa against a wall up to the wall. The box is where the object
    /// was seen to end (its mirror image where it was seen to continue).
    #[default]
    SeenOpenAndBeyond,
}

/// What the solid prior makes of the cells no view says anything of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UnseenCells {
    /// They stay unknown: no prior draws in them.
    Unknown,
    /// Those under the object are hidden: a cell whose column holds, above it and with only
    /// unseen cells between, a cell at the object's observed surface or hidden behind it. An
    /// object beside the camera's path is seen from above while its lower part stays below
    /// every frame's lower edge (a storage box the camera passes); what stands under its top
    /// reaches down to what it stands on.
    #[default]
    HiddenUnderTheObject,
}

/// The rules that pick the priors' cells: the solid prior's and the seen-free prior's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CellRules {
    /// Which hidden cells the solid prior takes.
    pub hidden: HiddenCells,
    /// Whether cells no view saw under the object count as hidden.
    pub unseen: UnseenCells,
    /// Which cells the seen-free prior takes.
    pub free: FreeCells,
}
