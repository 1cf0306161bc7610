//! Golf's contacts kept on a retargeted swing: planted feet stay planted, both hands stay on
//! one grip, the club head is at the ball at address and impact.
//!
//! A retargeter copies the coach's joint angles onto the student's bones; where the bodies
//! differ, angles alone lift a planted foot, open a gap between the hands or leave the club
//! head above the ball. [`Contacts::apply`] moves the retargeted swing back onto them, changing
//! as few angles as it can, in three passes over the frames (in place, `O(frames · joints)`;
//! [`Contacts::apply_by_frame`] makes them as one, a frame at a time, for a swing stored
//! otherwise):
//!
//! - **Feet.** Where the coach plants a foot (its toe where both skeletons have toes, else its
//!   ankle: [`feet`], within
//!   [`CONTACT_HEIGHT_M`] of its lowest point over the swing and moving slower than
//!   [`CONTACT_SPEED_M_S`] horizontally), the student's foot moves from where it was at the
//!   first frame of the contact only as the coach's does (a planted foot rolls and settles a
//!   little), not as the retargeting of the rest of the body carries it; after a contact the
//!   correction fades out over [`RELEASE_S`], so the foot leaves the ground without a jump. The leg reaches its goal by two-bone inverse
//!   kinematics (hip fixed, knee in its current bend plane); the foot is carried along
//!   unturned.
//! - **Grip** (a golf swing: the coach's [`Swing`] given). The trail wrist is moved along the
//!   line between the wrists (the line's direction is the retargeting's; wrists, which every
//!   format places alike) so that their distance is the coach's at address and at impact (both
//!   hands on one grip, whatever the arms' lengths): the retargeted distance is scaled by the
//!   ratio of the coach's to it at address, then at impact (within a factor of two),
//!   interpolated between and held outside, so that the coach's own frame-to-frame wobble of
//!   the gap never moves a still set-up (per frame, it moved the takeaway's timing by 9 ms at
//!   the median on the coaching benchmark). The trail arm reaches by two-bone
//!   inverse kinematics from the shoulder, carrying the hand unturned, and the lead arm keeps
//!   the coach's angles (its bend at the top is what a coach reads, and a nearly straight arm
//!   would need a large turn of the elbow for a centimetre of reach). The club hangs off the
//!   left hand, so for a left-handed golfer the trail wrist carries it; the club's pass below
//!   then puts its head back at the ball.
//! - **Club** (a golf swing, onto a target that carries a club). The club is
//!   turned about its grip, keeping its direction seen from above (a shaft within 3° of plumb
//!   is turned away from the body), so that its head is at the
//!   coach's club head height at address and at impact (the head's centre
//!   [`CLUB_HEAD_CLEARANCE_M`] above the floor where the coach tracks no club); the turn is
//!   interpolated between the two, held before address and faded out over [`RELEASE_S`]
//!   after impact.
//!
//! The floor is `y = 0` with `y` up, as in every reference the core retargets (the root's
//! trajectory is scaled about the origin, so the coach's floor stays the student's). Bone
//! lengths are kept exactly; a goal a limb cannot reach is approached as far as its length
//! allows.
//!
//! ```
//! use posecoach_core::contacts::{self, Contacts};
//! use posecoach_core::format::Format;
//! use posecoach_core::retarget::Analytic;
//! use posecoach_core::skeleton::Skeleton;
//! use posecoach_core::Vec3;
//!
//! let coach = Skeleton::standard(Format::H36m17).unwrap();
//! let longer: Vec<f32> = coach.offsets().iter().map(|o| 1.1 * o.norm()).collect();
//! let student = coach.with_bone_lengths(&longer).unwrap();
//! let mut frames = [Vec3::zeros(); 2 * 17];
//! coach.rest_positions(&mut frames[..17]);
//! coach.rest_positions(&mut frames[17..]);
//! let mut out = [Vec3::zeros(); 2 * 17];
//! let analytic = Analytic::new(&coach, &student).unwrap();
//! for (from, to) in frames.chunks_exact(17).zip(out.chunks_exact_mut(17)) {
//!     analytic.frame(from, to).unwrap();
//! }
//! let kept = Contacts::new(&coach, &student);
//! kept.apply(contacts::frames(&frames, 17), 30.0, None, &mut out).unwrap();
//! ```

use crate::config::MAX_JOINTS;
use crate::events::{Side, SwingEvents};
use crate::joint::Joint;
use crate::kinematics::{swing, LengthError};
use crate::math::norm;
use crate::skeleton::Skeleton;
use crate::{Quat, Vec3};
use core::cell::Cell;

/// A coach's foot counts as planted within this height above its lowest point (metres)...
pub const CONTACT_HEIGHT_M: f32 = 0.03;
/// ...while it moves slower than this horizontally (m/s).
pub const CONTACT_SPEED_M_S: f32 = 0.3;
/// A correction fades out over this long after its contact ends (seconds): about the time a
/// foot takes to leave the ground.
pub const RELEASE_S: f32 = 0.1;
/// The club head's centre above the floor at the ball, for a coach that tracks no club
/// (metres): half an iron's head.
pub const CLUB_HEAD_CLEARANCE_M: f32 = 0.03;

/// Why contacts could not be applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ContactError {
    /// The student's frames do not fill whole frames of its skeleton.
    Length(LengthError),
    /// The coach and the student have different numbers of frames (found by a caller that
    /// holds the coach's frames).
    #[allow(missing_docs)]
    Frames { coach: usize, student: usize },
    /// The address or impact frame is outside the swing, or impact is not after address.
    Events,
    /// A frame could not be read or written ([`Contacts::apply_by_frame`]'s caller said so).
    Frame(usize),
}

impl core::fmt::Display for ContactError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ContactError::Length(e) => e.fmt(f),
            ContactError::Frames { coach, student } => {
                write!(f, "the coach has {coach} frames, the student {student}")
            }
            ContactError::Events => f.write_str("address and impact are not frames of the swing"),
            ContactError::Frame(frame) => write!(f, "frame {frame} could not be read or written"),
        }
    }
}

impl core::error::Error for ContactError {}

/// Which contacts [`Contacts::apply`] keeps ([`Contacts::keeping`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Kept {
    /// Planted feet stay planted.
    pub feet: bool,
    /// Both hands on one grip.
    pub grip: bool,
    /// The club head at the ball at address and impact.
    pub club: bool,
}

impl Kept {
    /// Only the club at the ball (a motion whose body is right but whose club, of another
    /// length, misses it).
    pub const CLUB: Kept = Kept {
        feet: false,
        grip: false,
        club: true,
    };
}

/// What the contacts need of the coach's golf swing: its address and impact frames (where the
/// club is at the ball) and its lead side (whose arm keeps the coach's angles on the grip).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Swing {
    /// The address frame.
    pub address: usize,
    /// The impact frame.
    pub impact: usize,
    /// The lead side (the left for a right-handed golfer).
    pub lead: Side,
}

impl From<&SwingEvents> for Swing {
    fn from(events: &SwingEvents) -> Swing {
        Swing {
            address: events.address(),
            impact: events.impact(),
            lead: events.lead,
        }
    }
}

/// Two bones, `root → middle → end`, turned as one by [`Limb::reach`]: two-bone inverse
/// kinematics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limb {
    root: usize,
    middle: usize,
    end: usize,
    /// The joints below `end` (bit `k` = joint `k`), carried along with it.
    below: u64,
}

impl Limb {
    /// The limb ending at `end`, if `end`'s parent's parent is its root and the middle joint
    /// has no other child (so turning the two bones moves nothing else).
    pub fn new(skeleton: &Skeleton, end: Joint) -> Option<Limb> {
        let end = skeleton.index_of(end)?;
        let middle = skeleton.parent(end)?;
        let root = skeleton.parent(middle)?;
        let only_child =
            (0..skeleton.len()).all(|k| k == end || skeleton.parent(k) != Some(middle));
        only_child.then(|| Limb {
            root,
            middle,
            end,
            below: below(skeleton, end),
        })
    }

    /// Turns the two bones so that `end` reaches `goal`, or comes as near as the bones'
    /// lengths allow, keeping the plane the limb bends in; the joints below `end` are moved
    /// by the same amount as `end`. A `frame` shorter than the limb is left as it is.
    pub fn reach(&self, frame: &mut [Vec3], goal: Vec3) {
        let at = |k: usize| frame.get(k).copied();
        let (Some(s), Some(m), Some(e)) = (at(self.root), at(self.middle), at(self.end)) else {
            return;
        };
        let (a, b) = (norm(&(m - s)), norm(&(e - m)));
        let to = goal - s;
        let distance = norm(&to);
        // (Also false for NaN: a frame or goal that is not finite is left as it is.)
        let usable = |v: f32| v.is_finite() && v >= MIN_LENGTH;
        if !(usable(distance) && usable(a) && usable(b)) {
            return;
        }
        let u = to / distance;
        // Within reach (`max` then `min`: a bone shorter than the margin cannot panic).
        let d = distance
            .max((a - b).abs() + MIN_LENGTH)
            .min(a + b - MIN_LENGTH);
        // The middle joint: `x` along the root-to-goal line, `h` off it towards the current
        // bend.
        let x = (a * a - b * b + d * d) / (2.0 * d);
        let h = crate::math::sqrt((a * a - x * x).max(0.0));
        let bend = bend_direction(m - s, e - s, u);
        let end = s + u * d;
        frame[self.middle] = s + u * x + bend * h;
        let moved = end - e;
        frame[self.end] = end;
        for (k, p) in frame.iter_mut().enumerate() {
            if self.below & (1 << k) != 0 {
                *p += moved;
            }
        }
    }
}

/// The most the grip scales the retargeted gap by, or the least its inverse.
const MAX_GRIP_SCALE: f32 = 2.0;

/// The most frames a correction fades over.
const MAX_RELEASE: f32 = 1000.0;

/// Limb lengths and distances below this (metres) give no direction.
const MIN_LENGTH: f32 = 1e-6;

/// A shaft whose part seen from above is below this fraction of its length (within 3° of
/// plumb) has no direction there: a few millimetres would choose it.
const PLUMB: f32 = 0.05;

/// The unit direction, across `u`, in which a limb whose middle joint is at `middle` and end
/// at `end` (both from its root) bends: the middle joint's offset across the limb's own chord
/// (the plane it bends in now, whichever way its end is sent), else, for a straight limb, the
/// middle joint's offset across `u`, else any.
fn bend_direction(middle: Vec3, end: Vec3, u: Vec3) -> Vec3 {
    let across = |v: Vec3, axis: Vec3| v - axis * axis.dot(&v);
    let chord = norm(&end);
    let bent = match chord > MIN_LENGTH {
        true => across(middle, end / chord),
        false => Vec3::zeros(),
    };
    for v in [
        across(bent, u),
        across(middle, u),
        u.cross(&Vec3::x()),
        u.cross(&Vec3::z()),
    ] {
        let n = norm(&v);
        if n > MIN_LENGTH {
            return v / n;
        }
    }
    Vec3::zeros()
}

/// The joints below `k` in `skeleton` (bit `j` = joint `j`; `k` itself not included).
fn below(skeleton: &Skeleton, k: usize) -> u64 {
    (0..skeleton.len())
        .filter(|&j| j != k && skeleton.ancestry(j).any(|a| a == k))
        .fold(0, |mask, j| mask | 1 << j)
}

/// A foot: the student's leg, and the joint that touches the ground ([`feet`]) on the
/// student and on the coach.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Foot {
    leg: Limb,
    /// The student's joint that stays where the coach's is planted.
    contact: usize,
    /// The coach's joint whose contact decides.
    coach: usize,
}

/// Both hands on the grip: the student's arms, left then right, and the wrists whose gap is
/// kept, on the coach and on the student.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Grip {
    arms: [Limb; 2],
    coach: [usize; 2],
    student: [usize; 2],
}

/// The club on the student: its grip, and what turns with it about the grip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Club {
    grip: usize,
    head: usize,
    /// The joints below the grip, the head among them.
    below: u64,
    /// The coach's club head, if the coach tracks a club.
    coach_head: Option<usize>,
}

/// Golf's contacts for one coach skeleton and one student skeleton; which ones apply depends
/// on the joints both have (a student format without feet has no feet to plant).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Contacts {
    student_joints: usize,
    feet: [Option<Foot>; 2],
    grip: Option<Grip>,
    club: Option<Club>,
}

impl Contacts {
    /// The contacts between `coach`, whose motion was retargeted, and `student`, whose
    /// skeleton the retargeted swing is on.
    pub fn new(coach: &Skeleton, student: &Skeleton) -> Contacts {
        let ankles = [Joint::LeftAnkle, Joint::RightAnkle];
        let foot = |side: usize| {
            let [coach, contact] = feet(coach, student)[side]?;
            Some(Foot {
                leg: Limb::new(student, ankles[side])?,
                contact,
                coach,
            })
        };
        let arms = [Joint::LeftWrist, Joint::RightWrist].map(|w| Limb::new(student, w));
        // The wrists, which every format places alike (a hand joint is a knuckle in one, the
        // hand's centre in another).
        let wrists = |s: &Skeleton| {
            Some([
                s.index_of(Joint::LeftWrist)?,
                s.index_of(Joint::RightWrist)?,
            ])
        };
        let hands = wrists(coach).zip(wrists(student)).map(|(c, s)| [c, s]);
        let grip = match (arms, hands) {
            ([Some(l), Some(r)], Some([coach, student])) => Some(Grip {
                arms: [l, r],
                coach,
                student,
            }),
            _ => None,
        };
        let club = match (
            student.index_of(Joint::ClubGrip),
            student.index_of(Joint::ClubHead),
        ) {
            (Some(grip), Some(head)) if student.parent(head) == Some(grip) => Some(Club {
                grip,
                head,
                below: below(student, grip),
                coach_head: coach.index_of(Joint::ClubHead),
            }),
            _ => None,
        };
        Contacts {
            student_joints: student.len(),
            feet: [foot(0), foot(1)],
            grip,
            club,
        }
    }

    /// Only the contacts `kept` names (those the skeletons have).
    pub fn keeping(self, kept: Kept) -> Contacts {
        Contacts {
            feet: match kept.feet {
                true => self.feet,
                false => [None; 2],
            },
            grip: self.grip.filter(|_| kept.grip),
            club: self.club.filter(|_| kept.club),
            ..self
        }
    }

    /// The contacts these skeletons have to keep.
    pub fn kept(&self) -> Kept {
        Kept {
            feet: self.feet.iter().any(Option::is_some),
            grip: self.grip.is_some(),
            club: self.club.is_some(),
        }
    }

    /// Moves `student` (the coach's motion retargeted onto the student, frame after frame)
    /// onto the contacts of `coach`, the coach's motion it came from at `rate_hz`:
    /// `coach(f, k)` is the coach's joint `k` in frame `f` ([`frames`] reads a slice), for
    /// every frame of `student`. `swing`, the coach's address, impact and lead side, says the
    /// motion is a golf swing: without it only the feet are kept (hands on a grip and a club at
    /// the ball are golf's).
    ///
    /// # Errors
    /// [`ContactError::Length`] if `student` is not whole frames of its skeleton,
    /// [`ContactError::Events`] if address or impact is not a frame or impact is not after
    /// address. Nothing is written then.
    pub fn apply(
        &self,
        coach: impl Fn(usize, usize) -> Vec3,
        rate_hz: f32,
        swing: Option<Swing>,
        student: &mut [Vec3],
    ) -> Result<(), ContactError> {
        let m = self.student_joints;
        if m == 0 || !student.len().is_multiple_of(m) {
            return Err(ContactError::Length(LengthError {
                expected: m,
                actual: student.len(),
            }));
        }
        let frames = student.len() / m;
        // Read and written in place: no frame is read after it is written.
        let cells = Cell::from_mut(student).as_slice_of_cells();
        let read = |f: usize, out: &mut [Vec3]| match cells.get(f * m..(f + 1) * m) {
            Some(frame) => {
                for (o, p) in out.iter_mut().zip(frame) {
                    *o = p.get();
                }
                true
            }
            None => false,
        };
        let write = |f: usize, frame: &[Vec3]| match cells.get(f * m..(f + 1) * m) {
            Some(to) => {
                for (to, p) in to.iter().zip(frame) {
                    to.set(*p);
                }
                true
            }
            None => false,
        };
        self.apply_by_frame(coach, rate_hz, swing, frames, read, write)
    }

    /// [`Contacts::apply`] on a swing of `frames` frames read and written a frame at a time,
    /// for a swing not held as `f32` metres (a device keeps its virtual coach in millimetres):
    /// `read(f, out)` puts frame `f` as retargeted into `out` (the student's joints),
    /// `write(f, frame)` takes it moved onto the contacts; each returns whether it could. When
    /// the grip or the club is kept, the frames up to impact are read first (for their
    /// corrections at address and impact); then each frame is read and written, in order. No
    /// frame is read after it is written, so both may use one storage. The arithmetic is
    /// [`Contacts::apply`]'s, in the same order: the same frames to the bit.
    ///
    /// # Errors
    /// [`ContactError::Length`] for a student of no joints, [`ContactError::Events`] as for
    /// [`Contacts::apply`] (nothing read or written then); [`ContactError::Frame`] when `read`
    /// or `write` could not (the frames before it are written).
    pub fn apply_by_frame(
        &self,
        coach: impl Fn(usize, usize) -> Vec3,
        rate_hz: f32,
        swing: Option<Swing>,
        frames: usize,
        mut read: impl FnMut(usize, &mut [Vec3]) -> bool,
        mut write: impl FnMut(usize, &[Vec3]) -> bool,
    ) -> Result<(), ContactError> {
        let m = self.student_joints;
        if m == 0 || m > MAX_JOINTS {
            return Err(ContactError::Length(LengthError {
                expected: m,
                actual: 0,
            }));
        }
        if let Some(swing) = swing {
            if swing.address >= swing.impact || swing.impact >= frames {
                return Err(ContactError::Events);
            }
        }
        // A frame at least, a second's worth of frames at 10 kHz at most (a rate that is not
        // finite or not positive gives one).
        let release = match rate_hz.is_finite() && rate_hz > 0.0 {
            true => libm::roundf(RELEASE_S * rate_hz).clamp(1.0, MAX_RELEASE) as usize,
            false => 1,
        };
        let coach = &coach;
        let feet = self.feet.map(|foot| {
            foot.map(|foot| {
                let ground = Ground::new(coach, frames, foot.coach, rate_hz);
                (foot, ground, Planting::NEW)
            })
        });
        // Each foot in turn, each keeping its correction from frame to frame.
        let plant = |plants: &mut [Option<(Foot, Ground, Planting)>; 2], f, frame: &mut [Vec3]| {
            for (foot, ground, plant) in plants.iter_mut().flatten() {
                let (at, planted) = ground.next(coach, f);
                plant.step(foot, at, planted, frame, release);
            }
        };
        let mut pose = [Vec3::zeros(); MAX_JOINTS];
        let frame = &mut pose[..m];
        // The grip's scales and the club's turns, from the frames at address and impact as the
        // passes before each leave them.
        let mut golf = None;
        if let Some(swing) = swing.filter(|_| self.grip.is_some() || self.club.is_some()) {
            let mut plants = feet;
            let mut at = [[Vec3::zeros(); MAX_JOINTS]; 2];
            for f in 0..=swing.impact {
                if !read(f, frame) {
                    return Err(ContactError::Frame(f));
                }
                plant(&mut plants, f, frame);
                if let Some(k) = [swing.address, swing.impact].iter().position(|&e| e == f) {
                    at[k][..m].copy_from_slice(frame);
                }
            }
            let [address, impact] = &mut at;
            let (address, impact) = (&mut address[..m], &mut impact[..m]);
            let scales = self.grip.as_ref().map(|grip| {
                let scales = [
                    grip.ratio(coach, swing, swing.address, address),
                    grip.ratio(coach, swing, swing.impact, impact),
                ];
                grip.step(swing, scales, swing.address, address);
                grip.step(swing, scales, swing.impact, impact);
                scales
            });
            let turns = self.club.as_ref().map(|club| {
                [
                    club.turn(coach, swing.address, address),
                    club.turn(coach, swing.impact, impact),
                ]
            });
            golf = Some((swing, scales, turns));
        }
        let mut plants = feet;
        for f in 0..frames {
            if !read(f, frame) {
                return Err(ContactError::Frame(f));
            }
            plant(&mut plants, f, frame);
            if let Some((swing, scales, turns)) = golf {
                if let (Some(grip), Some(scales)) = (&self.grip, scales) {
                    grip.step(swing, scales, f, frame);
                }
                if let (Some(club), Some(turns)) = (&self.club, turns) {
                    club.step(swing, turns, release, f, frame);
                }
            }
            if !write(f, frame) {
                return Err(ContactError::Frame(f));
            }
        }
        Ok(())
    }
}

/// The joint of each foot, left then right, that touches the ground in `a` and in `b`: the
/// toes where both skeletons have them, else the ankles (the same joint on both sides, so that
/// an ankle is never held down by a toe's contact while the heel rises).
pub fn feet(a: &Skeleton, b: &Skeleton) -> [Option<[usize; 2]>; 2] {
    let both = |j: Joint| Some([a.index_of(j)?, b.index_of(j)?]);
    [
        both(Joint::LeftToe).or_else(|| both(Joint::LeftAnkle)),
        both(Joint::RightToe).or_else(|| both(Joint::RightAnkle)),
    ]
}

/// `positions` (whole frames of `joints` joints) as [`Contacts::apply`] reads a coach: joint
/// `k` of frame `f`, zero outside them.
pub fn frames(positions: &[Vec3], joints: usize) -> impl Fn(usize, usize) -> Vec3 + '_ {
    move |f, k| match k < joints {
        true => positions
            .get(f * joints + k)
            .copied()
            .unwrap_or_else(Vec3::zeros),
        false => Vec3::zeros(),
    }
}

/// A foot kept planted where the coach's is (see the module's documentation), frame after
/// frame: where its contact began, on the student and on the coach; the correction moving the
/// foot, and how many frames ago its contact ended.
#[derive(Clone, Copy, Debug)]
struct Planting {
    anchor: Vec3,
    start: Vec3,
    correction: Vec3,
    since: usize,
    was_planted: bool,
}

impl Planting {
    /// Before the first frame.
    const NEW: Planting = Planting {
        anchor: Vec3::new(0.0, 0.0, 0.0),
        start: Vec3::new(0.0, 0.0, 0.0),
        correction: Vec3::new(0.0, 0.0, 0.0),
        since: usize::MAX,
        was_planted: false,
    };

    /// Moves `foot` in `frame` (the one after the last), where the coach's contact is at `coach`
    /// and planted (`now`) or its correction fades.
    fn step(&mut self, foot: &Foot, coach: Vec3, now: bool, frame: &mut [Vec3], release: usize) {
        let free = frame[foot.contact];
        if now {
            if !self.was_planted {
                self.anchor = free + faded(self.correction, self.since, release);
                self.start = coach;
            }
            self.correction = self.anchor + (coach - self.start) - free;
            self.since = 0;
        } else if self.since != usize::MAX {
            self.since += 1;
        }
        self.was_planted = now;
        let moved = faded(self.correction, self.since, release);
        if moved != Vec3::zeros() {
            let goal = frame[foot.leg.end] + moved;
            foot.leg.reach(frame, goal);
        }
    }
}

/// A coach's contact joint read once a frame, frames in order from the first: where it is,
/// and whether it is planted there as [`planted`] says (each frame's reads of the coach, which
/// interpolates its frames in `f64`, made once).
#[derive(Clone, Copy, Debug)]
struct Ground {
    k: usize,
    count: usize,
    rate_hz: f32,
    lowest: f32,
    /// The joint in the frame before.
    before: Vec3,
}

impl Ground {
    /// Joint `k` of `count` frames of `coach` at `rate_hz`, before its first frame.
    fn new(coach: &impl Fn(usize, usize) -> Vec3, count: usize, k: usize, rate_hz: f32) -> Ground {
        Ground {
            k,
            count,
            rate_hz,
            lowest: (0..count)
                .map(|f| coach(f, k).y)
                .fold(f32::INFINITY, f32::min),
            before: Vec3::zeros(),
        }
    }

    /// The joint in frame `f`, the one after the last read (0 first), and whether it is
    /// planted.
    fn next(&mut self, coach: &impl Fn(usize, usize) -> Vec3, f: usize) -> (Vec3, bool) {
        let now = coach(f, self.k);
        let (a, b) = match f {
            0 => (now, coach(1.min(self.count.saturating_sub(1)), self.k)),
            _ => (self.before, now),
        };
        self.before = now;
        let step = b - a;
        let speed = crate::math::sqrt(step.x * step.x + step.z * step.z) * self.rate_hz;
        (
            now,
            now.y <= self.lowest + CONTACT_HEIGHT_M && speed < CONTACT_SPEED_M_S,
        )
    }
}

/// Whether joint `k` of the motion `at` (`at(f, k)`, as [`Contacts::apply`] reads a coach;
/// `count` frames at `rate_hz`) is planted in frame `f`: within [`CONTACT_HEIGHT_M`] of its
/// lowest point over all frames and moving slower than [`CONTACT_SPEED_M_S`] horizontally
/// since the frame before (the frame after, for the first).
pub fn planted(
    at: &impl Fn(usize, usize) -> Vec3,
    count: usize,
    k: usize,
    rate_hz: f32,
) -> impl Fn(usize) -> bool + '_ {
    let lowest = (0..count).map(|f| at(f, k).y).fold(f32::INFINITY, f32::min);
    move |f: usize| {
        let (a, b) = match f {
            0 => (0, 1.min(count.saturating_sub(1))),
            _ => (f - 1, f),
        };
        let step = at(b, k) - at(a, k);
        let speed = crate::math::sqrt(step.x * step.x + step.z * step.z) * rate_hz;
        at(f, k).y <= lowest + CONTACT_HEIGHT_M && speed < CONTACT_SPEED_M_S
    }
}

/// `correction` `since` frames after its contact ended, faded out linearly over `release`
/// frames (all of it during the contact, none once faded or if there was none).
fn faded(correction: Vec3, since: usize, release: usize) -> Vec3 {
    match since {
        s if s > release => Vec3::zeros(),
        s => correction * (1.0 - s as f32 / release.saturating_add(1) as f32),
    }
}

impl Grip {
    /// The student's lead and trail sides, 0 for the left and 1 for the right.
    fn sides(swing: Swing) -> (usize, usize) {
        match swing.lead {
            Side::Left => (0, 1),
            Side::Right => (1, 0),
        }
    }

    /// The ratio of the coach's gap between the wrists to `frame`'s (frame `f`): the scale
    /// that puts the trail wrist at the coach's distance from the lead wrist. A gap less than
    /// half or more than twice the coach's is a pose that scaling cannot mend (and a scale of
    /// it would carry the trail hand away mid-swing): 1 then.
    fn ratio(
        &self,
        coach: &impl Fn(usize, usize) -> Vec3,
        swing: Swing,
        f: usize,
        frame: &[Vec3],
    ) -> f32 {
        let (lead, trail) = Grip::sides(swing);
        let now = norm(&(frame[self.student[trail]] - frame[self.student[lead]]));
        let gap = norm(&(coach(f, self.coach[trail]) - coach(f, self.coach[lead])));
        match now > MIN_LENGTH && gap.is_finite() {
            true => (gap / now).clamp(1.0 / MAX_GRIP_SCALE, MAX_GRIP_SCALE),
            false => 1.0,
        }
    }

    /// Moves the trail wrist of `frame` (frame `f`) along the line between the wrists (the
    /// line the grip lies on; its direction is the retargeting's), its gap scaled by the
    /// `scales` at address and impact, interpolated between them and held outside: exact at
    /// the two moments the club is at the ball, smooth between, and never the coach's own
    /// frame-to-frame wobble (which moved the still set-up's hands). The lead arm keeps the
    /// coach's angles (its bend is what a coach reads).
    fn step(&self, swing: Swing, [at_address, at_impact]: [f32; 2], f: usize, frame: &mut [Vec3]) {
        let (lead, trail) = Grip::sides(swing);
        let [lead_wrist, trail_wrist] = [lead, trail].map(|k| self.student[k]);
        let t = match f {
            f if f <= swing.address => 0.0,
            f if f >= swing.impact => 1.0,
            f => (f - swing.address) as f32 / (swing.impact - swing.address) as f32,
        };
        let scale = at_address + (at_impact - at_address) * t;
        let apart = frame[trail_wrist] - frame[lead_wrist];
        self.arms[trail].reach(frame, frame[lead_wrist] + apart * scale);
    }
}

impl Club {
    /// The turn about the grip that puts the club head of `frame` (frame `f`) at the coach's
    /// height (see the module's documentation).
    fn turn(&self, coach: &impl Fn(usize, usize) -> Vec3, f: usize, frame: &[Vec3]) -> Quat {
        let height = match self.coach_head {
            Some(head) => coach(f, head).y,
            None => CLUB_HEAD_CLEARANCE_M,
        };
        let shaft = frame[self.head] - frame[self.grip];
        let length = norm(&shaft);
        let drop = height - frame[self.grip].y;
        // (False for NaN too: a club that is not finite is left as it is.)
        if !(length.is_finite() && drop.is_finite()) {
            return Quat::identity();
        }
        // Seen from above: the shaft's direction, or for a shaft within PLUMB of plumb, the
        // way from the root (the pelvis) to the grip, as far as that is known (the ball is in
        // front of the hands). Across PLUMB the direction may jump; no golfer's shaft hangs
        // plumb at address or impact.
        let away = frame[self.grip] - frame[0];
        let least = (PLUMB * length).max(MIN_LENGTH);
        let Some((x, z)) = [shaft, away].into_iter().find_map(|v| {
            let across = crate::math::sqrt(v.x * v.x + v.z * v.z);
            (across >= least).then(|| (v.x / across, v.z / across))
        }) else {
            return Quat::identity();
        };
        let drop = drop.max(-length).min(length);
        let spread = crate::math::sqrt((length * length - drop * drop).max(0.0));
        swing(shaft, Vec3::new(x * spread, drop, z * spread))
    }

    /// Turns the club of `frame` (frame `f`) about its grip: the `turns` at address and
    /// impact, interpolated between them, held before address and faded out over `release`
    /// frames after impact.
    fn step(
        &self,
        Swing {
            address, impact, ..
        }: Swing,
        [at_address, at_impact]: [Quat; 2],
        release: usize,
        f: usize,
        frame: &mut [Vec3],
    ) {
        let q = if f <= address {
            at_address
        } else if f <= impact {
            blend(
                at_address,
                at_impact,
                (f - address) as f32 / (impact - address) as f32,
            )
        } else {
            let t = ((f - impact) as f32 / release.saturating_add(1) as f32).min(1.0);
            blend(at_impact, Quat::identity(), t)
        };
        let grip = frame[self.grip];
        for (k, p) in frame.iter_mut().enumerate() {
            if self.below & (1 << k) != 0 {
                *p = grip + q * (*p - grip);
            }
        }
    }
}

/// The normalized linear blend of two turns, `t` of the way from `a` to `b`, the short way
/// round (`b` as its opposite quaternion, the same turn, where theirs is the long way).
fn blend(a: Quat, b: Quat, t: f32) -> Quat {
    let b = match a.coords.dot(&b.coords) < 0.0 {
        true => Quat::new_unchecked(-b.into_inner()),
        false => b,
    };
    a.nlerp(&b, t)
}

/// The most joints a [`Limb`]'s or [`Club`]'s bitset can name.
const _: () = assert!(MAX_JOINTS <= 64);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;
    use crate::retarget::Analytic;

    extern crate std;
    use std::vec;
    use std::vec::Vec;

    /// A coach standing still on `frames` frames, then swaying: the skeleton, its frames.
    fn coach(format: Format, frames: usize, sway: impl Fn(usize) -> Vec3) -> (Skeleton, Vec<Vec3>) {
        let skeleton = Skeleton::standard(format).unwrap();
        let n = skeleton.len();
        let mut rest = vec![Vec3::zeros(); n];
        skeleton.rest_positions(&mut rest);
        let floor = rest.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        let mut out = Vec::with_capacity(frames * n);
        for f in 0..frames {
            out.extend(
                rest.iter()
                    .map(|p| p + Vec3::new(0.0, -floor, 0.0) + sway(f)),
            );
        }
        (skeleton, out)
    }

    fn retarget(coach: &Skeleton, frames: &[Vec3], student: &Skeleton) -> Vec<Vec3> {
        let analytic = Analytic::new(coach, student).unwrap();
        let mut out = vec![Vec3::zeros(); frames.len() / coach.len() * student.len()];
        for (from, to) in frames
            .chunks_exact(coach.len())
            .zip(out.chunks_exact_mut(student.len()))
        {
            analytic.frame(from, to).unwrap();
        }
        out
    }

    /// Each elbow of `frames` (whole frames of `skeleton`) put halfway between its shoulder and
    /// wrist and 5 cm lower, as arms that reach forward bend.
    fn bend_elbows(skeleton: &Skeleton, frames: &mut [Vec3]) {
        let n = skeleton.len();
        for frame in frames.chunks_exact_mut(n) {
            for [shoulder, elbow, wrist] in [
                [Joint::LeftShoulder, Joint::LeftElbow, Joint::LeftWrist],
                [Joint::RightShoulder, Joint::RightElbow, Joint::RightWrist],
            ] {
                let [s, e, w] = [shoulder, elbow, wrist].map(|j| skeleton.index_of(j).unwrap());
                frame[e] = (frame[s] + frame[w]) * 0.5 - Vec3::new(0.0, 0.05, 0.0);
            }
        }
    }

    /// `skeleton` with each bone `k` scaled by `factor(k)`.
    fn scaled(skeleton: &Skeleton, factor: impl Fn(usize) -> f32) -> Skeleton {
        let lengths: Vec<f32> = (0..skeleton.len())
            .map(|k| norm(&skeleton.offset(k)) * factor(k))
            .collect();
        skeleton.with_bone_lengths(&lengths).unwrap()
    }

    fn bone_lengths(skeleton: &Skeleton, frame: &[Vec3]) -> Vec<f32> {
        (1..skeleton.len())
            .map(|k| norm(&(frame[k] - frame[skeleton.parent(k).unwrap()])))
            .collect()
    }

    #[test]
    fn every_standard_format_has_its_feet_and_grip() {
        for format in Format::BUILT_IN {
            let s = Skeleton::standard(format).unwrap();
            let c = Contacts::new(&s, &s);
            let kept = c.kept();
            assert!(kept.feet && kept.grip, "{format:?}");
        }
    }

    #[test]
    fn planted_feet_stay_while_the_hips_sway_and_bones_keep_their_lengths() {
        // The coach's hips sway 10 cm to the side and sink 15 cm over a second (under Miri,
        // which takes a second over each frame, over a third of one); the student's legs are
        // longer, so the analytic retargeter scales the sway and the feet slide with it.
        const LAST: usize = if cfg!(miri) { 10 } else { 30 };
        let sway = |f: usize| Vec3::new(0.0033, -0.005, 0.0) * (f * (30 / LAST)) as f32;
        let (s, frames) = coach(Format::H36m17, LAST + 1, sway);
        let student = scaled(&s, |k| if (1..7).contains(&k) { 1.2 } else { 1.0 });
        // Only the hips sway: the coach's feet stay (a planted stance).
        let mut frames = frames;
        let feet = [
            s.index_of(Joint::LeftAnkle).unwrap(),
            s.index_of(Joint::RightAnkle).unwrap(),
        ];
        for f in 1..=LAST {
            for &k in &feet {
                frames[f * 17 + k] = frames[k];
            }
        }
        let mut out = retarget(&s, &frames, &student);
        let ankles = [
            student.index_of(Joint::LeftAnkle).unwrap(),
            student.index_of(Joint::RightAnkle).unwrap(),
        ];
        let moved = |o: &[Vec3]| norm(&(o[LAST * 17 + ankles[0]] - o[ankles[0]]));
        assert!(moved(&out) > 0.01, "the analytic retargeter's feet slide");
        let lengths = bone_lengths(&student, &out[..17]);
        Contacts::new(&s, &student)
            .apply(super::frames(&frames, s.len()), 30.0, None, &mut out)
            .unwrap();
        for f in 0..=LAST {
            for &k in &ankles {
                assert!(norm(&(out[f * 17 + k] - out[k])) < 1e-4, "frame {f}");
            }
            let now = bone_lengths(&student, &out[f * 17..(f + 1) * 17]);
            for (a, b) in now.iter().zip(&lengths) {
                assert!((a - b).abs() < 1e-4);
            }
        }
    }

    #[test]
    fn a_lifted_foot_is_released_without_a_jump() {
        // The coach's left foot stays for 10 frames, then rises 1 cm a frame.
        let (s, mut frames) = coach(Format::H36m17, 30, |f| {
            Vec3::new(0.003 * f as f32, 0.0, 0.0)
        });
        let ankle = s.index_of(Joint::LeftAnkle).unwrap();
        for f in 1..30 {
            let lift = if f < 10 { 0.0 } else { 0.01 * (f - 9) as f32 };
            frames[f * 17 + ankle] = frames[ankle] + Vec3::new(0.0, lift, 0.0);
        }
        let student = scaled(&s, |_| 1.15);
        let mut out = retarget(&s, &frames, &student);
        let free = out.clone();
        Contacts::new(&s, &student)
            .apply(super::frames(&frames, s.len()), 30.0, None, &mut out)
            .unwrap();
        let steps: Vec<f32> = (1..30)
            .map(|f| norm(&(out[f * 17 + ankle] - out[(f - 1) * 17 + ankle])))
            .collect();
        let largest = steps.iter().copied().fold(0.0, f32::max);
        let free_largest = (1..30)
            .map(|f| norm(&(free[f * 17 + ankle] - free[(f - 1) * 17 + ankle])))
            .fold(0.0, f32::max);
        assert!(
            largest < 1.5 * free_largest,
            "{largest} against {free_largest}"
        );
        // Faded out: after the release the foot is the retargeter's.
        assert!(norm(&(out[29 * 17 + ankle] - free[29 * 17 + ankle])) < 1e-6);
    }

    #[test]
    fn the_wrists_keep_the_coachs_gap() {
        let (s, frames) = coach(Format::H36m17, 5, |f| Vec3::new(0.0, 0.0, 0.01 * f as f32));
        let mut frames = frames;
        let [l, r] = [Joint::LeftWrist, Joint::RightWrist].map(|j| s.index_of(j).unwrap());
        // Hands in front of the chest, 20 cm apart: the arms reach forward.
        for f in 0..5 {
            let chest = frames[f * 17 + s.index_of(Joint::Thorax).unwrap()];
            frames[f * 17 + l] = chest + Vec3::new(0.1, -0.2, 0.35);
            frames[f * 17 + r] = chest + Vec3::new(-0.1, -0.2, 0.35);
        }
        bend_elbows(&s, &mut frames);
        // The student is broader.
        let student = scaled(&s, |k| if k >= 11 { 1.1 } else { 1.0 });
        let mut out = retarget(&s, &frames, &student);
        let gap = |o: &[Vec3], f: usize| o[f * 17 + r] - o[f * 17 + l];
        assert!((norm(&gap(&out, 0)) - 0.2).abs() > 0.01);
        let contacts = Contacts::new(&s, &student);
        // Not a golf swing: the hands are free.
        let mut free = out.clone();
        contacts
            .apply(super::frames(&frames, s.len()), 30.0, None, &mut free)
            .unwrap();
        for f in 0..5 {
            assert_eq!(gap(&free, f), gap(&out, f));
        }
        contacts
            .apply(
                super::frames(&frames, s.len()),
                30.0,
                Some(Swing {
                    address: 1,
                    impact: 3,
                    lead: Side::Left,
                }),
                &mut out,
            )
            .unwrap();
        // A gap that does not change: its distance is the coach's in every frame.
        for f in 0..5 {
            let miss = norm(&gap(&out, f)) - norm(&gap(&frames, f));
            assert!(miss.abs() < 1e-4, "frame {f}: {miss}");
        }
    }

    #[test]
    fn the_club_head_is_at_the_coachs_height_at_address_and_impact() {
        // Leaning 17 degrees forward, plumb, and 1 degree forward (within 3 degrees of plumb).
        // Under Miri, which takes a second over each frame, the first alone: the others read
        // and move the same joints of the same frames.
        let leans: &[f32] = if cfg!(miri) {
            &[0.3]
        } else {
            &[0.3, 0.0, 0.02]
        };
        for &lean in leans {
            club_at_the_coachs_height(lean);
        }
    }

    /// The coach's club points down and `lean` forward from the grip (0: plumb; 0.3 leans
    /// more each frame); the student's is longer, so the analytic retargeter puts its head
    /// into the floor.
    fn club_at_the_coachs_height(lean: f32) {
        let (s, mut frames) = coach(Format::GolfMarkers, 20, |_| Vec3::zeros());
        let n = s.len();
        let [grip, head] = [Joint::ClubGrip, Joint::ClubHead].map(|j| s.index_of(j).unwrap());
        let length = norm(&s.offset(head));
        for f in 0..20 {
            let forward = if lean > 0.1 {
                lean + 0.01 * f as f32
            } else {
                lean
            };
            let down = Vec3::new(0.0, -0.95, forward).normalize();
            frames[f * n + head] = frames[f * n + grip] + down * length;
        }
        let student = scaled(&s, |k| if k == head { 1.2 } else { 1.0 });
        let mut out = retarget(&s, &frames, &student);
        let contacts = Contacts::new(&s, &student);
        assert!(contacts.kept().club);
        let [address, impact] = [3, 12];
        assert!((out[address * n + head].y - frames[address * n + head].y).abs() > 0.05);
        contacts
            .apply(
                super::frames(&frames, s.len()),
                30.0,
                Some(Swing {
                    address,
                    impact,
                    lead: Side::Left,
                }),
                &mut out,
            )
            .unwrap();
        for f in [address, impact] {
            let missed = out[f * n + head].y - frames[f * n + head].y;
            assert!(missed.abs() < 1e-4, "lean {lean}, frame {f}: {missed}");
            let shaft = out[f * n + head] - out[f * n + grip];
            assert!((norm(&shaft) - 1.2 * length).abs() < 1e-4);
            // Seen from above, a leaning shaft keeps its direction (forward, +z); one within
            // 3 degrees of plumb swings the way from the root to the grip.
            let away = out[f * n + grip] - out[f * n];
            let expected = match lean > 0.1 {
                true => Vec3::z(),
                false => Vec3::new(away.x, 0.0, away.z),
            };
            let across = Vec3::new(shaft.x, 0.0, shaft.z);
            assert!(
                across.normalize().dot(&expected.normalize()) > 0.9999,
                "lean {lean}, frame {f}: {across:?} against {expected:?}"
            );
        }
        assert_eq!(
            contacts.apply(
                super::frames(&frames, s.len()),
                30.0,
                Some(Swing {
                    address: 12,
                    impact: 3,
                    lead: Side::Left
                }),
                &mut out
            ),
            Err(ContactError::Events)
        );
    }

    /// [`Contacts::apply`] as it was written before [`Contacts::apply_by_frame`]: each foot,
    /// then the grip, then the club, one pass over all the frames each.
    fn in_passes(
        contacts: &Contacts,
        coach: &impl Fn(usize, usize) -> Vec3,
        rate_hz: f32,
        swing: Swing,
        student: &mut [Vec3],
    ) {
        let m = contacts.student_joints;
        let frames = student.len() / m;
        let release = libm::roundf(RELEASE_S * rate_hz) as usize;
        for foot in contacts.feet.iter().flatten() {
            let planted = planted(coach, frames, foot.coach, rate_hz);
            let mut plant = Planting::NEW;
            for (f, frame) in student.chunks_exact_mut(m).enumerate() {
                plant.step(foot, coach(f, foot.coach), planted(f), frame, release);
            }
        }
        if let Some(grip) = &contacts.grip {
            let at =
                |f: usize, student: &[Vec3]| grip.ratio(coach, swing, f, &student[f * m..][..m]);
            let scales = [at(swing.address, student), at(swing.impact, student)];
            for (f, frame) in student.chunks_exact_mut(m).enumerate() {
                grip.step(swing, scales, f, frame);
            }
        }
        if let Some(club) = &contacts.club {
            let at = |f: usize| club.turn(coach, f, &student[f * m..][..m]);
            let turns = [at(swing.address), at(swing.impact)];
            for (f, frame) in student.chunks_exact_mut(m).enumerate() {
                club.step(swing, turns, release, f, frame);
            }
        }
    }

    #[test]
    fn a_frame_at_a_time_is_every_pass_in_turn_to_the_bit_and_reads_no_frame_it_wrote() {
        // A golfer with a club whose hips sway and whose left foot lifts after impact, onto a
        // student of longer legs, arms and club: every contact moves something.
        const FRAMES: usize = 24;
        let (s, mut frames) = coach(Format::GolfMarkers, FRAMES, |f| {
            Vec3::new(0.004 * f as f32, -0.002 * f as f32, 0.001 * f as f32)
        });
        let n = s.len();
        let [toe, head] = [Joint::LeftToe, Joint::ClubHead].map(|j| s.index_of(j).unwrap());
        for f in 0..FRAMES {
            frames[f * n + toe] =
                frames[toe] + Vec3::new(0.0, 0.01 * f.saturating_sub(14) as f32, 0.0);
            frames[f * n + head] += Vec3::new(0.0, -0.02, 0.01 * f as f32);
        }
        bend_elbows(&s, &mut frames);
        let student = scaled(&s, |k| 1.0 + 0.02 * (k % 7) as f32);
        let retargeted = retarget(&s, &frames, &student);
        let contacts = Contacts::new(&s, &student);
        assert_eq!(
            contacts.kept(),
            Kept {
                feet: true,
                grip: true,
                club: true
            }
        );
        let coach = super::frames(&frames, n);
        let swing = Swing {
            address: 4,
            impact: 13,
            lead: Side::Left,
        };
        let mut expected = retargeted.clone();
        in_passes(&contacts, &coach, 30.0, swing, &mut expected);
        assert!(expected
            .iter()
            .zip(&retargeted)
            .any(|(a, b)| norm(&(a - b)) > 0.01));
        let mut in_place = retargeted.clone();
        contacts
            .apply(&coach, 30.0, Some(swing), &mut in_place)
            .unwrap();
        let mut written = vec![Vec3::zeros(); retargeted.len()];
        let log = core::cell::RefCell::new(Vec::new());
        let read = |f: usize, out: &mut [Vec3]| {
            log.borrow_mut().push((f, false));
            out.copy_from_slice(&retargeted[f * n..(f + 1) * n]);
            true
        };
        let write = |f: usize, frame: &[Vec3]| {
            log.borrow_mut().push((f, true));
            written[f * n..(f + 1) * n].copy_from_slice(frame);
            true
        };
        contacts
            .apply_by_frame(&coach, 30.0, Some(swing), FRAMES, read, write)
            .unwrap();
        let bits = |v: &[Vec3]| {
            v.iter()
                .flat_map(|p| p.iter().map(|x| x.to_bits()))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&in_place), bits(&expected));
        assert_eq!(bits(&written), bits(&expected));
        let log = log.into_inner();
        // Up to impact once to find the corrections, then each frame read and written in turn.
        let first: Vec<_> = (0..=swing.impact).map(|f| (f, false)).collect();
        let then: Vec<_> = (0..FRAMES).flat_map(|f| [(f, false), (f, true)]).collect();
        assert_eq!(log, [first, then].concat());
        // A frame that cannot be read or written stops the work there.
        let mut out = vec![Vec3::zeros(); retargeted.len()];
        let refused = contacts.apply_by_frame(
            &coach,
            30.0,
            Some(swing),
            FRAMES,
            |f, out| {
                out.copy_from_slice(&retargeted[f * n..(f + 1) * n]);
                f != 7
            },
            |f, frame| {
                out[f * n..(f + 1) * n].copy_from_slice(frame);
                f != 20
            },
        );
        assert_eq!(refused, Err(ContactError::Frame(7)));
        let refused = contacts.apply_by_frame(
            &coach,
            30.0,
            None,
            FRAMES,
            |f, out| {
                out.copy_from_slice(&retargeted[f * n..(f + 1) * n]);
                true
            },
            |f, _| f != 20,
        );
        assert_eq!(refused, Err(ContactError::Frame(20)));
    }

    #[test]
    fn the_grip_is_the_coachs_at_address_and_impact_and_the_lead_arm_is_untouched() {
        // The coach's wrists 8 cm apart at address, 12 cm at impact (frames 2 and 8); the
        // student's arms are longer, so the retargeted gap is wider.
        let (s, mut frames) = coach(Format::H36m17, 11, |_| Vec3::zeros());
        let [l, r, thorax] =
            [Joint::LeftWrist, Joint::RightWrist, Joint::Thorax].map(|j| s.index_of(j).unwrap());
        for f in 0..11 {
            let gap = 0.08 + 0.04 * (f as f32 / 10.0);
            let chest = frames[f * 17 + thorax];
            frames[f * 17 + l] = chest + Vec3::new(gap / 2.0, -0.3, 0.3);
            frames[f * 17 + r] = chest + Vec3::new(-gap / 2.0, -0.3, 0.3);
        }
        bend_elbows(&s, &mut frames);
        let student = scaled(&s, |k| if k >= 11 { 1.25 } else { 1.0 });
        let mut out = retarget(&s, &frames, &student);
        let free = out.clone();
        let swing = Swing {
            address: 2,
            impact: 8,
            lead: Side::Left,
        };
        Contacts::new(&s, &student)
            .apply(super::frames(&frames, 17), 30.0, Some(swing), &mut out)
            .unwrap();
        let gap = |o: &[Vec3], f: usize| norm(&(o[f * 17 + r] - o[f * 17 + l]));
        for f in [2, 8] {
            assert!((gap(&out, f) - gap(&frames, f)).abs() < 1e-4, "frame {f}");
        }
        for f in 0..11 {
            // The lead arm as retargeted; the trail wrist on the line between the wrists.
            for k in [11, 12, 13] {
                assert_eq!(out[f * 17 + k], free[f * 17 + k], "frame {f}");
            }
            let (before, after) = (
                free[f * 17 + r] - free[f * 17 + l],
                out[f * 17 + r] - out[f * 17 + l],
            );
            assert!(norm(&before.cross(&after)) < 1e-4 * norm(&before) * norm(&after).max(1.0));
        }
    }

    #[test]
    fn a_bent_knee_keeps_its_side() {
        // A leg bent slightly forward, its foot sent forward and up: the knee still points
        // forward (+z), as it did.
        let s = Skeleton::standard(Format::H36m17).unwrap();
        let leg = Limb::new(&s, Joint::LeftAnkle).unwrap();
        let mut frame = [Vec3::zeros(); 17];
        s.rest_positions(&mut frame);
        let (hip, ankle) = (frame[leg.root], frame[leg.end]);
        frame[leg.middle] = (hip + ankle) * 0.5 + Vec3::new(0.0, 0.0, 0.01);
        leg.reach(&mut frame, ankle + Vec3::new(0.0, 0.1, 0.15));
        let knee = frame[leg.middle] - hip;
        let chord = frame[leg.end] - hip;
        let side = knee - chord * (chord.dot(&knee) / chord.norm_squared());
        assert!(side.z > 0.0, "{side:?}");
    }

    #[test]
    fn input_that_is_not_finite_or_empty_is_refused_or_left_without_a_panic() {
        let (s, frames) = coach(Format::GolfMarkers, 6, |f| {
            Vec3::new(0.01 * f as f32, 0.0, 0.0)
        });
        let n = s.len();
        let contacts = Contacts::new(&s, &s);
        let swing = Some(Swing {
            address: 1,
            impact: 4,
            lead: Side::Right,
        });
        for rate in [0.0, -30.0, f32::NAN, f32::INFINITY, 1e30] {
            let mut out = frames.clone();
            contacts
                .apply(super::frames(&frames, n), rate, swing, &mut out)
                .unwrap();
        }
        for bad in [f32::NAN, f32::INFINITY, 3e38] {
            let mut coach_frames = frames.clone();
            coach_frames[2 * n + 3] = Vec3::new(bad, bad, 0.0);
            let mut out = frames.clone();
            out[3 * n] = Vec3::new(bad, -bad, bad);
            contacts
                .apply(super::frames(&coach_frames, n), 30.0, swing, &mut out)
                .unwrap();
        }
        let mut empty: [Vec3; 0] = [];
        assert_eq!(
            contacts.apply(super::frames(&frames, n), 30.0, None, &mut empty),
            Ok(())
        );
        assert_eq!(
            contacts.apply(super::frames(&frames, n), 30.0, swing, &mut empty),
            Err(ContactError::Events)
        );
        let mut short = frames[..n + 1].to_vec();
        assert!(matches!(
            contacts.apply(super::frames(&frames, n), 30.0, None, &mut short),
            Err(ContactError::Length(_))
        ));
        let at_end = Some(Swing {
            address: 1,
            impact: 6,
            lead: Side::Left,
        });
        let mut out = frames.clone();
        assert_eq!(
            contacts.apply(super::frames(&frames, n), 30.0, at_end, &mut out),
            Err(ContactError::Events)
        );
    }

    /// [`bones_keep_their_lengths`]'s swings have fewer frames than this, their address before
    /// half of it: fewer under Miri, which takes a second over each frame.
    const MOST_FRAMES: usize = if cfg!(miri) { 12 } else { 40 };

    proptest::proptest! {
        /// Whatever the coach does and whatever the student's proportions, every bone keeps
        /// its length and nothing becomes NaN.
        #[test]
        fn bones_keep_their_lengths(
            steps in proptest::collection::vec((-0.05f32..0.05, -0.05f32..0.05, -0.05f32..0.05), 2..MOST_FRAMES),
            limbs in 0.7f32..1.4,
            address in 0..MOST_FRAMES / 2,
        ) {
            let (s, mut frames) = coach(Format::GolfMarkers, steps.len(), |_| Vec3::zeros());
            let n = s.len();
            // Every joint wanders by the running sum of the steps, the feet by a tenth of it.
            let mut drift = Vec3::zeros();
            for (f, &(x, y, z)) in steps.iter().enumerate() {
                drift += Vec3::new(x, y, z);
                for k in 0..n {
                    let share = if s.joint(k).is_some_and(|j| matches!(j, Joint::LeftAnkle | Joint::RightAnkle | Joint::LeftToe | Joint::RightToe)) { 0.1 } else { 1.0 };
                    frames[f * n + k] += drift * share * (1.0 + k as f32 / n as f32);
                }
            }
            let student = scaled(&s, |k| if k % 2 == 0 { limbs } else { 1.0 });
            let mut out = retarget(&s, &frames, &student);
            let lengths = bone_lengths(&student, &out[..n]);
            let swing = (address + 1 < steps.len()).then(|| Swing {
                address,
                impact: steps.len() - 1,
                lead: Side::Right,
            });
            Contacts::new(&s, &student).apply(super::frames(&frames, n), 30.0, swing, &mut out).unwrap();
            for frame in out.chunks_exact(n) {
                proptest::prop_assert!(frame.iter().all(|p| p.iter().all(|c| c.is_finite())));
                for (a, b) in bone_lengths(&student, frame).iter().zip(&lengths) {
                    proptest::prop_assert!((a - b).abs() < 1e-4 * b.max(1.0), "{a} against {b}");
                }
            }
        }
    }
}
