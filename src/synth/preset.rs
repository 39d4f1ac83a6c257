//! Scene presets: image size, frame count, room size and which furniture to place.

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::furniture::Design;
use super::room::Room;
use crate::error::CatmapError;
use crate::sensor::frame::CameraIntrinsics;

/// A named scene configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// 160×120, 30 frames, 6 objects (three identical ladder-back chairs, the table, a stool and a
    /// lamp): fast enough for unit and pipeline tests.
    Small,
    /// 640×480, 240 frames, 13–15 objects: three or four of each chair design, the table, a
    /// cabinet, a box, a lamp, a stool, a nightstand and a sofa against a wall.
    Default,
    /// 640×480, 240 frames, 11–12 objects of a living-bedroom: a bed, a sofa and a bookcase
    /// against the walls, two nightstands, two or three armchairs, two ladder-back chairs, a
    /// lamp and a box. Large unique objects seen from one side.
    Living,
}

/// How many of each design a preset asks for, and how many chairs to tuck under the table.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Furnishing {
    /// Designs in object-id order (id = position + 1).
    pub designs: Vec<Design>,
    /// Chairs to push (partly) under the table.
    pub tucked_chairs: usize,
}

impl Preset {
    /// Every preset.
    pub const ALL: [Preset; 3] = [Self::Small, Self::Default, Self::Living];

    /// Lowercase name, as in `scene.json` and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Small => "small",
            Self::Default => "default",
            Self::Living => "living",
        }
    }

    /// Camera intrinsics: the preset's width (small 160, default and living 640) in
    /// [`camera_of_width`].
    pub fn intrinsics(self) -> CameraIntrinsics {
        camera_of_width(match self {
            Self::Small => 160,
            Self::Default | Self::Living => 640,
        })
    }

    /// Number of frames of the trajectory.
    pub fn frame_count(self) -> usize {
        match self {
            Self::Small => 30,
            Self::Default | Self::Living => 240,
        }
    }

    /// The room.
    pub fn room(self) -> Room {
        match self {
            Self::Small => Room {
                half_x_m: 2.5,
                half_y_m: 2.25,
                height_m: 2.6,
            },
            Self::Default | Self::Living => Room {
                half_x_m: 3.5,
                half_y_m: 3.0,
                height_m: 2.7,
            },
        }
    }

    /// The furniture, given two numbers in `[0, 1)` drawn from the scene's generator (they pick
    /// the chair counts and how many chairs are tucked).
    pub fn furnishing(self, draws: [f32; 2]) -> Furnishing {
        let pick =
            |draw: f32, options: &[usize]| options[((draw * options.len() as f32) as usize).min(options.len() - 1)];
        match self {
            Self::Small => Furnishing {
                designs: [
                    [Design::LadderBackChair; 3].as_slice(),
                    &[Design::DiningTable, Design::Stool, Design::FloorLamp],
                ]
                .concat(),
                tucked_chairs: pick(draws[0], &[1, 2]),
            },
            Self::Default => {
                let ladder_backs = pick(draws[0], &[3, 4]);
                let armchairs = pick(draws[1], &[3, 4]);
                let mut designs = vec![Design::LadderBackChair; ladder_backs];
                designs.extend(std::iter::repeat_n(Design::Armchair, armchairs));
                designs.extend([
                    Design::DiningTable,
                    Design::Cabinet,
                    Design::StorageBox,
                    Design::FloorLamp,
                    Design::Stool,
                    Design::Nightstand,
                    Design::Sofa,
                ]);
                Furnishing {
                    designs,
                    tucked_chairs: pick((draws[0] + draws[1]) / 2.0, &[2, 3]),
                }
            }
            Self::Living => {
                let mut designs = vec![Design::Armchair; pick(draws[0], &[2, 3])];
                designs.extend([
                    Design::LadderBackChair,
                    Design::LadderBackChair,
                    Design::Nightstand,
                    Design::Nightstand,
                    Design::Bed,
                    Design::Sofa,
                    Design::Bookcase,
                    Design::FloorLamp,
                    Design::StorageBox,
                ]);
                Furnishing {
                    designs,
                    tucked_chairs: 0,
                }
            }
        }
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Preset {
    type Err = CatmapError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| CatmapError::ConfigValue(format!("unknown synthetic preset {s:?} (small, default, living)")))
    }
}

/// The synthetic camera `width` pixels wide: 4:3, focal length 0.8 × width (≈ 64° horizontal
/// field of view), centred principal point.
pub fn camera_of_width(width: u32) -> CameraIntrinsics {
    CameraIntrinsics::centred(width, width * 3 / 4, 0.8 * width as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_preset_has_three_or_more_of_each_chair_a_sofa_and_twelve_to_sixteen_objects() {
        for draws in [[0.0, 0.0], [0.99, 0.99], [0.2, 0.7]] {
            let f = Preset::Default.furnishing(draws);
            let count = |d: Design| f.designs.iter().filter(|&&x| x == d).count();
            assert!(count(Design::LadderBackChair) >= 3 && count(Design::Armchair) >= 3);
            assert_eq!(count(Design::Sofa), 1, "one large unique object against a wall");
            assert!((12..=16).contains(&f.designs.len()), "{} objects", f.designs.len());
        }
    }

    #[test]
    fn living_preset_has_the_three_wall_pieces_once_and_pairs_of_the_rest() {
        for draws in [[0.0, 0.0], [0.99, 0.99]] {
            let f = Preset::Living.furnishing(draws);
            let count = |d: Design| f.designs.iter().filter(|&&x| x == d).count();
            for large in [Design::Bed, Design::Sofa, Design::Bookcase] {
                assert_eq!(count(large), 1, "{}", large.name());
            }
            assert!(count(Design::Nightstand) == 2 && count(Design::Armchair) >= 2);
        }
    }

    #[test]
    fn presets_parse_from_their_names() {
        for preset in Preset::ALL {
            assert_eq!(preset.name().parse::<Preset>().expect("known name"), preset);
        }
        assert!("huge".parse::<Preset>().is_err());
        let k = Preset::Small.intrinsics();
        let hfov = 2.0 * (k.width as f32 / 2.0 / k.fx).atan();
        assert!(
            (60f32.to_radians()..70f32.to_radians()).contains(&hfov),
            "horizontal FOV {hfov}"
        );
    }
}
