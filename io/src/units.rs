//! Length units and the up axis of a file that does not state them, found from the body in it.
//!
//! Units are read from the stature: a golfer is [`GOLFER_STATURE_M`] tall, and of metres,
//! centimetres, millimetres and inches exactly one puts any stature in that range (the range
//! spans a factor of 2.3, the closest two units 2.54). The up axis is the one the body's
//! feet-to-head direction follows ([`Up::detect`]).

use posecoach_core::Vec3;
use std::fmt;
use std::ops::RangeInclusive;
use std::str::FromStr;

/// The statures read as a golfer's, metres: a keypoint file whose body falls outside in every
/// unit is refused rather than scored (children from about six years to the tallest players).
pub const GOLFER_STATURE_M: RangeInclusive<f32> = 1.0..=2.3;

/// A length unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Units {
    /// Metres.
    M,
    /// Centimetres.
    Cm,
    /// Millimetres.
    Mm,
    /// Inches.
    In,
    /// The unit of CMU's BVH conversions, 1/0.45 inch.
    Cmu,
}

impl Units {
    /// Every unit.
    pub const ALL: [Units; 5] = [Units::M, Units::Cm, Units::Mm, Units::In, Units::Cmu];
    /// The units keypoint files are read in.
    pub const KEYPOINT: [Units; 4] = [Units::M, Units::Cm, Units::Mm, Units::In];

    /// Metres per unit.
    pub fn metres(self) -> f32 {
        match self {
            Units::M => 1.0,
            Units::Cm => 0.01,
            Units::Mm => 0.001,
            Units::In => 0.0254,
            Units::Cmu => 0.0254 / 0.45,
        }
    }

    /// The unit's symbol, as `--units` takes it.
    pub const fn symbol(self) -> &'static str {
        match self {
            Units::M => "m",
            Units::Cm => "cm",
            Units::Mm => "mm",
            Units::In => "in",
            Units::Cmu => "cmu",
        }
    }

    /// The unit of [`Units::ALL`] that makes a stature of `height` (file units) closest to
    /// 1.75 m on a log scale: BVH files do not state their units.
    pub fn nearest(height: f32) -> Units {
        let off = |u: &Units| (height * u.metres() / 1.75).ln().abs();
        Units::ALL
            .into_iter()
            .min_by(|a, b| off(a).total_cmp(&off(b)))
            .unwrap_or(Units::M)
    }

    /// The unit of [`Units::KEYPOINT`] in which a stature of `height` (file units) is a
    /// golfer's ([`GOLFER_STATURE_M`]).
    ///
    /// # Errors
    /// [`StatureError`] with the height when no unit makes it a golfer's.
    pub fn detect(height: f32) -> Result<Units, StatureError> {
        Units::KEYPOINT
            .into_iter()
            .find(|u| GOLFER_STATURE_M.contains(&(height * u.metres())))
            .ok_or(StatureError {
                height,
                given: None,
            })
    }

    /// Checks that a stature of `height` in `self` is a golfer's.
    ///
    /// # Errors
    /// [`StatureError`] when it is not.
    pub fn check(self, height: f32) -> Result<Units, StatureError> {
        if GOLFER_STATURE_M.contains(&(height * self.metres())) {
            Ok(self)
        } else {
            Err(StatureError {
                height,
                given: Some(self),
            })
        }
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.symbol())
    }
}

impl FromStr for Units {
    type Err = String;
    fn from_str(s: &str) -> Result<Units, String> {
        Units::ALL
            .into_iter()
            .find(|u| u.symbol() == s)
            .ok_or_else(|| format!("`{s}` is not a unit: expected m, cm, mm, in or cmu"))
    }
}

/// A body that is no golfer's size: its stature in the file's units, and the unit given, if
/// one was.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StatureError {
    /// The stature in the file's units.
    pub height: f32,
    /// The unit given with `--units`.
    pub given: Option<Units>,
}

impl fmt::Display for StatureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (lo, hi) = (GOLFER_STATURE_M.start(), GOLFER_STATURE_M.end());
        match self.given {
            Some(u) => write!(
                f,
                "the body is {:.3} m tall in {u}, outside a golfer's {lo} to {hi} m: check the units \
                 (--units m, cm, mm or in) or the joints",
                self.height * u.metres()
            ),
            None => write!(
                f,
                "the body is {} tall in the file's units, which is a golfer's {lo} to {hi} m in none \
                 of m, cm, mm or in: check the joints",
                self.height
            ),
        }
    }
}

impl std::error::Error for StatureError {}

/// Which way is up in a file: an axis and its sign.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Up {
    /// 0, 1, 2 for x, y, z.
    pub axis: u8,
    /// Whether up is the axis's negative direction (image coordinates: +y down).
    pub negative: bool,
}

impl Up {
    /// +Y up, posecoach's own convention.
    pub const Y: Up = Up {
        axis: 1,
        negative: false,
    };

    /// The rotation (a proper one: handedness kept) that turns this up onto +Y, applied to `v`.
    pub fn to_y_up(self, v: Vec3) -> Vec3 {
        let (x, y, z) = (v.x, v.y, v.z);
        match (self.axis, self.negative) {
            (0, false) => Vec3::new(-y, x, z),
            (0, true) => Vec3::new(y, -x, z),
            (2, false) => Vec3::new(x, z, -y),
            (2, true) => Vec3::new(x, -z, y),
            (_, true) => Vec3::new(x, -y, -z),
            _ => v,
        }
    }

    /// The up of a body whose mean feet-to-head vector is `rise`: its largest component, where
    /// that is at least twice each other one (a golfer at address leans well under that).
    pub fn detect(rise: Vec3) -> Option<Up> {
        let a = rise.abs();
        let axis = (0..3).max_by(|&i, &j| a[i].total_cmp(&a[j]))?;
        let dominant = (0..3).all(|j| j == axis || a[axis] >= 2.0 * a[j]);
        (dominant && a[axis] > 0.0).then_some(Up {
            axis: axis as u8,
            negative: rise[axis] < 0.0,
        })
    }
}

impl fmt::Display for Up {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sign = if self.negative { "-" } else { "+" };
        write!(
            f,
            "{sign}{}",
            ["x", "y", "z"][usize::from(self.axis.min(2))]
        )
    }
}

impl FromStr for Up {
    type Err = String;
    fn from_str(s: &str) -> Result<Up, String> {
        let (negative, name) = match s.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, s.strip_prefix('+').unwrap_or(s)),
        };
        let axis = match name {
            "x" | "X" => 0,
            "y" | "Y" => 1,
            "z" | "Z" => 2,
            _ => {
                return Err(format!(
                    "`{s}` is not an axis: expected x, y, z, -x, -y or -z"
                ))
            }
        };
        Ok(Up { axis, negative })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn exactly_one_keypoint_unit_makes_any_golfer() {
        for cm in 100..=230 {
            let metres = cm as f32 / 100.0;
            for u in Units::KEYPOINT {
                let fits: Vec<Units> = Units::KEYPOINT
                    .into_iter()
                    .filter(|v| GOLFER_STATURE_M.contains(&(metres / u.metres() * v.metres())))
                    .collect();
                assert_eq!(fits, [u], "{metres} m in {u}");
                assert_eq!(Units::detect(metres / u.metres()), Ok(u));
            }
        }
        let e = Units::detect(2037e3).unwrap_err();
        assert!(e.to_string().contains("2037000 tall"), "{e}");
        let e = Units::M.check(2037.0).unwrap_err();
        assert!(e.to_string().contains("2037.000 m tall in m"), "{e}");
    }

    #[test]
    fn every_up_turns_onto_plus_y_and_keeps_handedness() {
        for axis in 0..3u8 {
            for negative in [false, true] {
                let up = Up { axis, negative };
                let mut v = Vec3::zeros();
                v[usize::from(axis)] = if negative { -1.0 } else { 1.0 };
                assert_eq!(up.to_y_up(v), Vec3::y(), "{up}");
                let (a, b) = (Vec3::x(), Vec3::z());
                let turned = up.to_y_up(a).cross(&up.to_y_up(b));
                assert!((turned - up.to_y_up(a.cross(&b))).norm() < 1e-6, "{up}");
                assert_eq!(up.to_string().parse::<Up>(), Ok(up));
                assert_eq!(Up::detect(v * 1.5 + Vec3::new(0.2, 0.2, 0.2)), Some(up));
            }
        }
        assert_eq!(Up::detect(Vec3::new(1.0, 0.8, 0.0)), None);
        assert_eq!(Up::detect(Vec3::zeros()), None);
    }
}
