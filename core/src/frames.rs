//! A swing as it is stored, frame after frame of joint positions, and how it is read.
//!
//! Positions are kept either as `f32` metres (a motion read from a file, a virtual coach on the
//! host) or as 16-bit millimetres ([`Mm`]: a device's ring of live frames and its virtual
//! coach, in half the RAM, and the coach references in flash, [`crate::reference`], in half the
//! flash); every reader of a swing (events, body metrics, the sequence, the alignment, the
//! score) takes [`Frames`] and sees metres either way. A millimetre position is the metre one
//! rounded to the nearest millimetre, so it is off by at most 0.5 mm an axis (0.87 mm in all);
//! [`to_mm`] refuses what is not finite or lies outside −32.768 m to 32.767 m. Millimetres may
//! also be read turned about the vertical ([`Frames::millimetres_turned`], a [`Turn`]): a
//! stored swing faced another way for one comparison without being rounded again.
//!
//! ```
//! use posecoach_core::frames::{to_mm, Frames};
//! use posecoach_core::Vec3;
//!
//! let metres = [Vec3::new(0.1, 1.0, 0.0), Vec3::new(0.2, 1.5, -0.0004)];
//! let mm = [to_mm(&metres[0]).unwrap(), to_mm(&metres[1]).unwrap()];
//! let swing = Frames::millimetres(&mm, 2);
//! assert_eq!(swing.len(), 1);
//! assert!((swing.at(0, 1) - metres[1]).norm() < 1e-3);
//! ```

use crate::config::MAX_JOINTS;
use crate::Vec3;
use core::ops::Range;

/// A position in millimetres, x, y and z.
pub type Mm = [i16; 3];

/// `p` (metres) to the nearest millimetre; `None` when an axis is not finite or its
/// millimetres lie outside `i16` (−32.768 m to 32.767 m).
pub fn to_mm(p: &Vec3) -> Option<Mm> {
    let axis = |v: f32| {
        // Rounded half away from zero as `libm::roundf` rounds (it truncates this sum), the
        // truncation the conversion's own: one instruction, not a call for each axis.
        let mm = v * 1000.0;
        let away = mm + libm::copysignf(0.5 - 0.25 * f32::EPSILON, mm);
        // Truncated to −32 768 to 32 767; NaN fails both comparisons.
        (away > -32769.0 && away < 32768.0).then_some(away as i16)
    };
    Some([axis(p.x)?, axis(p.y)?, axis(p.z)?])
}

/// `p` in metres: each axis the `f32` nearest its millimetres.
pub fn from_mm(p: Mm) -> Vec3 {
    Vec3::new(
        f32::from(p[0]) / 1000.0,
        f32::from(p[1]) / 1000.0,
        f32::from(p[2]) / 1000.0,
    )
}

/// A turn about the vertical (+Y) through a point: `p` becomes
/// `origin + (cos·d.x + sin·d.z, d.y, −sin·d.x + cos·d.z)` with `d = p − origin`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Turn {
    origin: Vec3,
    sin: f32,
    cos: f32,
}

impl Turn {
    /// The turn through `origin` by the angle whose sine and cosine are `sin` and `cos`
    /// (right-handed about +Y: +Z toward +X).
    pub fn new(origin: Vec3, sin: f32, cos: f32) -> Turn {
        Turn { origin, sin, cos }
    }

    /// `p` turned.
    #[inline]
    pub fn apply(&self, p: &Vec3) -> Vec3 {
        let (sin, cos) = (self.sin, self.cos);
        let d = p - self.origin;
        self.origin + Vec3::new(cos * d.x + sin * d.z, d.y, -sin * d.x + cos * d.z)
    }

    /// The direction `v` turned back (the inverse turn, without the point it turns about).
    #[inline]
    pub fn back(&self, v: &Vec3) -> Vec3 {
        let (sin, cos) = (self.sin, self.cos);
        Vec3::new(cos * v.x - sin * v.z, v.y, sin * v.x + cos * v.z)
    }
}

/// `p` in metres, turned. (Out of line, so that [`Frames::at`] stays small enough to inline
/// for the other storages.)
#[inline(never)]
fn turned(p: Mm, turn: &Turn) -> Vec3 {
    turn.apply(&from_mm(p))
}

/// Whole frames of `joints` positions each, frame-major, as they are stored; a partial frame
/// at the end is not read.
#[derive(Clone, Copy, Debug)]
pub struct Frames<'a> {
    stored: Stored<'a>,
    joints: usize,
}

/// How the positions are stored.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Stored<'a> {
    /// `f32` metres.
    Metres(&'a [Vec3]),
    /// 16-bit millimetres.
    Millimetres(&'a [Mm]),
    /// 16-bit millimetres, each position turned as it is read.
    Turned(&'a [Mm], &'a Turn),
}

impl<'a> Frames<'a> {
    /// `positions` in metres, `joints` to a frame.
    pub fn metres(positions: &'a [Vec3], joints: usize) -> Frames<'a> {
        Frames {
            stored: Stored::Metres(positions),
            joints,
        }
    }

    /// `positions` in millimetres, `joints` to a frame.
    pub fn millimetres(positions: &'a [Mm], joints: usize) -> Frames<'a> {
        Frames {
            stored: Stored::Millimetres(positions),
            joints,
        }
    }

    /// `positions` in millimetres, `joints` to a frame, each read as [`Frames::millimetres`]
    /// reads it, then turned by `turn`.
    pub fn millimetres_turned(positions: &'a [Mm], joints: usize, turn: &'a Turn) -> Frames<'a> {
        Frames {
            stored: Stored::Turned(positions, turn),
            joints,
        }
    }

    /// Positions in a frame.
    pub fn joints(&self) -> usize {
        self.joints
    }

    /// Positions stored, whole frames or not.
    fn stored_len(&self) -> usize {
        match self.stored {
            Stored::Metres(p) => p.len(),
            Stored::Millimetres(p) | Stored::Turned(p, _) => p.len(),
        }
    }

    /// Whole frames.
    pub fn len(&self) -> usize {
        self.stored_len().checked_div(self.joints).unwrap_or(0)
    }

    /// Whether there is no whole frame.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the positions are a whole number of frames, at least one joint to a frame.
    pub fn is_whole(&self) -> bool {
        self.joints > 0 && self.stored_len().is_multiple_of(self.joints)
    }

    /// Whether every position is finite (millimetres always are).
    pub fn is_finite(&self) -> bool {
        match self.stored {
            Stored::Metres(p) => p.iter().all(|p| p.iter().all(|v| v.is_finite())),
            Stored::Millimetres(_) | Stored::Turned(..) => true,
        }
    }

    /// Joint `joint` (below [`Frames::joints`]) of frame `frame`, metres.
    ///
    /// # Panics
    /// When the position lies beyond the storage: callers index within [`Frames::len`] and
    /// [`Frames::joints`] (a joint beyond a frame's would read the next frame's).
    #[inline]
    pub fn at(&self, frame: usize, joint: usize) -> Vec3 {
        let k = frame * self.joints + joint;
        match self.stored {
            Stored::Metres(p) => p[k],
            Stored::Millimetres(p) => from_mm(p[k]),
            Stored::Turned(p, turn) => turned(p[k], turn),
        }
    }

    /// Frame `frame`, metres, in `out`'s first [`Frames::joints`] positions (at most
    /// [`MAX_JOINTS`]).
    ///
    /// # Panics
    /// As [`Frames::at`].
    pub fn frame<'o>(&self, frame: usize, out: &'o mut [Vec3; MAX_JOINTS]) -> &'o [Vec3] {
        let out = &mut out[..self.joints.min(MAX_JOINTS)];
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.at(frame, k);
        }
        out
    }

    /// Every position of the whole frames, frame after frame, metres.
    pub fn iter(&self) -> impl Iterator<Item = Vec3> + 'a {
        let (frames, joints) = (*self, self.joints);
        (0..frames.len() * joints).map(move |k| frames.at(k / joints, k % joints))
    }

    /// The frames in `frames`; `None` when they are not all here.
    pub fn get(&self, frames: Range<usize>) -> Option<Frames<'a>> {
        let (from, to) = (frames.start * self.joints, frames.end * self.joints);
        let stored = match self.stored {
            Stored::Metres(p) => Stored::Metres(p.get(from..to)?),
            Stored::Millimetres(p) => Stored::Millimetres(p.get(from..to)?),
            Stored::Turned(p, turn) => Stored::Turned(p.get(from..to)?, turn),
        };
        Some(Frames {
            stored,
            joints: self.joints,
        })
    }

    /// The positions as stored, whole frames or not, when they are stored in metres: for a
    /// reader that takes a slice of metres (`None` for millimetres).
    pub fn as_metres(&self) -> Option<&'a [Vec3]> {
        match self.stored {
            Stored::Metres(p) => Some(p),
            Stored::Millimetres(_) | Stored::Turned(..) => None,
        }
    }

    /// How the positions are stored, for readers with a loop for each.
    pub(crate) fn stored(&self) -> Stored<'a> {
        self.stored
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn out_of_range_or_non_finite_positions_have_no_millimetres() {
        assert_eq!(
            to_mm(&Vec3::new(32.767, -32.768, 0.0)),
            Some([32767, -32768, 0])
        );
        assert_eq!(to_mm(&Vec3::new(32.768, 0.0, 0.0)), None);
        assert_eq!(to_mm(&Vec3::new(0.0, -32.7686, 0.0)), None);
        assert_eq!(to_mm(&Vec3::new(0.0, 0.0, f32::NAN)), None);
        assert_eq!(to_mm(&Vec3::new(f32::INFINITY, 0.0, 0.0)), None);
    }

    #[test]
    fn both_storages_read_alike_and_cut_whole_frames() {
        let metres: [Vec3; 7] = core::array::from_fn(|k| Vec3::new(k as f32, -0.5, 0.25));
        let mm = metres.map(|p| to_mm(&p).unwrap());
        for frames in [Frames::metres(&metres, 3), Frames::millimetres(&mm, 3)] {
            assert_eq!(
                (frames.len(), frames.joints(), frames.is_whole()),
                (2, 3, false)
            );
            assert_eq!(frames.at(1, 2), metres[5]);
            let mut out = [Vec3::zeros(); MAX_JOINTS];
            assert_eq!(frames.frame(1, &mut out), &metres[3..6]);
            assert!(frames.iter().eq(metres[..6].iter().copied()));
            let cut = frames.get(1..2).unwrap();
            assert_eq!((cut.len(), cut.at(0, 0)), (1, metres[3]));
            assert!(frames.get(1..3).is_none());
        }
        assert_eq!(Frames::metres(&metres, 3).as_metres(), Some(&metres[..]));
        assert!(Frames::millimetres(&mm, 3).as_metres().is_none());
        assert!(Frames::metres(&metres[..6], 3).is_whole());
        assert!(!Frames::metres(&metres, 0).is_whole());
        assert_eq!(Frames::metres(&metres, 0).len(), 0);
    }

    #[test]
    fn turned_millimetres_read_as_their_metres_turned() {
        const QUARTER: (f32, f32) = (1.0, 0.0);
        let metres: [Vec3; 6] = core::array::from_fn(|k| Vec3::new(0.5 + k as f32, 1.0, -0.25));
        let mm = metres.map(|p| to_mm(&p).unwrap());
        let turn = Turn::new(Vec3::new(0.5, 0.0, 0.0), QUARTER.0, QUARTER.1);
        let turned = Frames::millimetres_turned(&mm, 3, &turn);
        assert_eq!((turned.len(), turned.is_finite()), (2, true));
        assert!(turned.as_metres().is_none());
        // A quarter turn through (0.5, 0, 0): +X goes to −Z, −Z to −X.
        let p = turned.at(1, 0);
        assert!((p - Vec3::new(0.25, 1.0, -3.0)).norm() < 1e-6, "{p:?}");
        for (k, p) in turned.iter().enumerate() {
            assert_eq!(p, turn.apply(&metres[k]));
        }
        let cut = turned.get(1..2).unwrap();
        assert_eq!(cut.at(0, 2), turned.at(1, 2));
        let back = turn.back(&(turned.at(1, 2) - turned.at(1, 0)));
        assert!((back - (metres[5] - metres[3])).norm() < 1e-6, "{back:?}");
    }

    #[test]
    fn millimetres_are_libm_s_rounding() {
        const EDGES: [f32; 14] = [
            0.0,
            -0.0,
            0.0005,
            -0.0005,
            0.0015,
            0.00049999997,
            -0.0025,
            1e-9,
            32.7674,
            32.7675,
            -32.7684,
            -32.7685,
            7.0000005,
            -0.1234565,
        ];
        let libm_s = |v: f32| {
            let mm = libm::roundf(v * 1000.0);
            (-32768.0..=32767.0).contains(&mm).then_some(mm as i16)
        };
        // Under Miri, which takes a second over a few hundred, fewer draws.
        const DRAWS: usize = if cfg!(miri) { 200 } else { 20_000 };
        let mut v = 0.3f32;
        let draws = (0..DRAWS).map(|_| {
            v = (v * 7919.0 + 0.123).rem_euclid(70.0) - 35.0;
            v
        });
        for v in EDGES.into_iter().chain(draws) {
            let ours = to_mm(&Vec3::new(v, 0.0, 0.0)).map(|p| p[0]);
            assert_eq!(ours, libm_s(v), "{v}");
        }
    }

    proptest! {
        #[test]
        fn rounding_is_libm_s(v in -40.0f32..40.0) {
            let mm = libm::roundf(v * 1000.0);
            let expected = (-32768.0..=32767.0).contains(&mm).then_some(mm as i16);
            prop_assert_eq!(to_mm(&Vec3::new(0.0, v, 0.0)).map(|p| p[1]), expected);
        }

        #[test]
        fn a_position_comes_back_within_half_a_millimetre_an_axis(
            x in -32.7f32..32.7, y in -32.7f32..32.7, z in -32.7f32..32.7,
        ) {
            let p = Vec3::new(x, y, z);
            let back = from_mm(to_mm(&p).unwrap());
            for axis in 0..3 {
                prop_assert!((back[axis] - p[axis]).abs() <= 0.5e-3 + 4e-6);
            }
        }
    }
}
