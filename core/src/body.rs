//! Body metrics: the angles and shifts golf coaches read a swing by, measured from joint
//! positions in the golfer's [`Stance`] frame.
//!
//! Every golfer is measured as if right-handed: positions are taken in the stance frame, whose
//! first axis points from the trail foot to the lead foot, so a left-handed golfer's metrics
//! read like a right-handed golfer's mirror image, with the same signs.
//!
//! - **Stance frame** (fixed at address): origin between the feet, `target` from the trail foot
//!   toward the lead foot (horizontal), `ball` the horizontal direction the chest faces, `up`.
//! - **Segments**: the *pelvis* has its lateral axis from the trail hip to the lead hip; the
//!   *thorax* from the trail shoulder to the lead shoulder. The thorax's long axis runs from the
//!   spine joint (else the pelvis) to the thorax joint (else the neck, else between the
//!   shoulders); the pelvis's from the pelvis to the same thorax point, the trunk: joint
//!   centres carry no pelvic tilt, so the pelvis's bend is the trunk's. A segment's forward
//!   axis is perpendicular to both of its axes, out of the chest; its long axis is made
//!   perpendicular to the lateral one.
//! - **Angles** of a segment, degrees, relative to the stance frame, in the order of the
//!   segment-angle reports of golf motion capture (rotation, then bend, then side bend): *turn*
//!   about the vertical, positive closed (facing away from the target, as at the top), negative
//!   open; *bend* about the segment's own lateral axis, positive forward (toward the ball);
//!   *side bend* about the segment's own forward axis, positive toward the trail side (the
//!   trail hip or shoulder lower, as at address and impact). All zero when standing square to
//!   the target line, upright. The three are Euler angles: every orientation has one set
//!   while the bend is within ±90°.
//! - **Shifts** from address, metres, in the stance frame: *sway* toward the target, *thrust*
//!   toward the ball, *lift* up; of the pelvis (between the hips), the thorax (its joint,
//!   else between the shoulders) and the head.
//! - **X-factor**: thorax turn less pelvis turn, degrees.
//! - **Spine angle**: the trunk (pelvis to thorax) from the vertical as seen down the target
//!   line, degrees, positive leaning toward the ball.
//! - **Lead arm across the chest**: the lead arm (shoulder to wrist) in the thorax's transverse
//!   plane, from the thorax's lateral axis toward its forward axis, degrees: 0 along the
//!   shoulder line toward the target, 90 straight out from the chest, past 90 across it.
//!   Meaningful when the arm is raised (P3 to P5, P9); a hanging arm is near the plane's normal.
//! - **Lead elbow**: its flexion, degrees, 0 straight.
//! - Where a club is tracked: **shaft lean**, the shaft (head to grip) from the vertical as
//!   seen face on, degrees, positive with the grip toward the target; **wrist hinge**, the angle
//!   between the lead forearm and the shaft (grip to head), degrees, 0 in line.
//!
//! ```
//! use posecoach_core::body::{Body, Stance};
//! use posecoach_core::events::Side;
//! use posecoach_core::format::Format;
//! use posecoach_core::skeleton::Skeleton;
//! use posecoach_core::Vec3;
//!
//! let skeleton = Skeleton::standard(Format::H36m17).unwrap();
//! let mut pose = [Vec3::zeros(); 17];
//! skeleton.rest_positions(&mut pose);
//! let stance = Stance::new(&skeleton, &pose, Side::Left);
//! let body = Body::new(&skeleton, Side::Left).unwrap();
//! let metrics = body.measure(&stance, &pose, &pose).unwrap();
//! assert_eq!(body.measure(&stance, &pose, &pose[..3]), None);
//! assert!(metrics.thorax.turn.abs() < 1.0 && metrics.x_factor.abs() < 1.0);
//! assert_eq!(metrics.pelvis_shift.sway, 0.0);
//! ```

use crate::config::MAX_JOINTS;
use crate::events::{Position, Side, SwingEvents, SMOOTHING_S};
use crate::frames::Frames;
use crate::joint::Joint;
use crate::skeleton::Skeleton;
use crate::Vec3;

/// A golfer's stance frame at address (see the [module documentation](self)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stance {
    origin: Vec3,
    target: Vec3,
    ball: Vec3,
}

impl Stance {
    /// The stance of the address `frame` of a golfer whose lead side is `lead`. Joints the
    /// skeleton lacks count as at the origin; feet together face +X.
    pub fn new(skeleton: &Skeleton, frame: &[Vec3], lead: Side) -> Stance {
        let at = |joints: &[Joint]| skeleton.find(joints).map_or(Vec3::zeros(), |k| frame[k]);
        let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z);
        let (left, right) = (
            at(&[Joint::LeftAnkle, Joint::LeftToe]),
            at(&[Joint::RightAnkle, Joint::RightToe]),
        );
        let (lead_foot, trail_foot) = match lead {
            Side::Left => (left, right),
            Side::Right => (right, left),
        };
        let target = flat(lead_foot - trail_foot)
            .try_normalize(1e-6)
            .unwrap_or(Vec3::x());
        // The golfer bends over the ball: the chest leans out past the hips toward it. (The
        // hands hang almost straight below the shoulders, too close to tell.)
        let mut ball = Vec3::y().cross(&target);
        let lean = at(&[Joint::Thorax, Joint::Neck]) - at(&[Joint::Pelvis]);
        if ball.dot(&lean) < 0.0 {
            ball = -ball;
        }
        let origin = (left + right) * 0.5;
        Stance {
            origin: Vec3::new(origin.x, 0.0, origin.z),
            target,
            ball,
        }
    }

    /// The horizontal unit vector from the trail foot toward the lead foot.
    pub fn toward_target(&self) -> Vec3 {
        self.target
    }

    /// The horizontal unit vector toward the ball.
    pub fn toward_ball(&self) -> Vec3 {
        self.ball
    }

    /// The point between the feet at address, on the ground (`y` = 0).
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// `p` as (toward the target, toward the ball, up) from between the feet.
    pub fn local(&self, p: Vec3) -> Vec3 {
        self.direction(p - self.origin)
    }

    /// The direction or offset `d` as (toward the target, toward the ball, up).
    pub fn direction(&self, d: Vec3) -> Vec3 {
        Vec3::new(d.dot(&self.target), d.dot(&self.ball), d.y)
    }

    /// The point whose [`Stance::local`] coordinates are `local`.
    pub fn world(&self, local: Vec3) -> Vec3 {
        self.origin + self.target * local.x + self.ball * local.y + Vec3::y() * local.z
    }
}

/// A segment's orientation in the stance frame, degrees (see the [module
/// documentation](self) for axes and signs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Angles {
    /// About the vertical: positive closed (away from the target), negative open.
    pub turn: f32,
    /// About the segment's lateral axis: positive forward, toward the ball.
    pub bend: f32,
    /// About the segment's forward axis: positive toward the trail side.
    pub side_bend: f32,
}

/// How far a point has moved since address, metres, in the stance frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Shift {
    /// Toward the target.
    pub sway: f32,
    /// Toward the ball.
    pub thrust: f32,
    /// Up.
    pub lift: f32,
}

/// The body metrics of one frame (see the [module documentation](self)).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Metrics {
    /// The pelvis's turn, bend and side bend.
    pub pelvis: Angles,
    /// The thorax's turn, bend and side bend.
    pub thorax: Angles,
    /// Thorax turn less pelvis turn, degrees.
    pub x_factor: f32,
    /// The trunk from the vertical seen down the target line, degrees.
    pub spine: f32,
    /// The pelvis (between the hips) since address.
    pub pelvis_shift: Shift,
    /// The thorax since address.
    pub thorax_shift: Shift,
    /// The head since address, where the skeleton has a head joint.
    pub head_shift: Option<Shift>,
    /// The lead arm across the chest, degrees.
    pub lead_arm: f32,
    /// The lead elbow's flexion, degrees.
    pub lead_elbow: f32,
    /// The shaft from the vertical seen face on, degrees, where a club is tracked.
    pub shaft_lean: Option<f32>,
    /// Lead forearm to shaft, degrees, where a club is tracked.
    pub wrist_hinge: Option<f32>,
}

/// How many values a [`Metrics`] holds ([`Metrics::values`]).
const VALUES: usize = 21;

impl Metrics {
    /// Every value, in the order the struct declares them (each [`Angles`] and [`Shift`] in
    /// its own; NaN for one the skeleton cannot give), for arithmetic on all of them at once.
    fn values(&self) -> [f32; VALUES] {
        let (a, b) = (self.pelvis, self.thorax);
        let [p, t] = [self.pelvis_shift, self.thorax_shift];
        let h = self.head_shift.unwrap_or(Shift {
            sway: f32::NAN,
            thrust: f32::NAN,
            lift: f32::NAN,
        });
        [
            a.turn,
            a.bend,
            a.side_bend,
            b.turn,
            b.bend,
            b.side_bend,
            self.x_factor,
            self.spine,
            p.sway,
            p.thrust,
            p.lift,
            t.sway,
            t.thrust,
            t.lift,
            h.sway,
            h.thrust,
            h.lift,
            self.lead_arm,
            self.lead_elbow,
            self.shaft_lean.unwrap_or(f32::NAN),
            self.wrist_hinge.unwrap_or(f32::NAN),
        ]
    }

    /// These metrics with every value replaced by `values` (as [`Metrics::values`] orders
    /// them), those absent here left absent.
    fn with_values(&self, v: [f32; VALUES]) -> Metrics {
        let angles = |k: usize| Angles {
            turn: v[k],
            bend: v[k + 1],
            side_bend: v[k + 2],
        };
        let shift = |k: usize| Shift {
            sway: v[k],
            thrust: v[k + 1],
            lift: v[k + 2],
        };
        Metrics {
            pelvis: angles(0),
            thorax: angles(3),
            x_factor: v[6],
            spine: v[7],
            pelvis_shift: shift(8),
            thorax_shift: shift(11),
            head_shift: self.head_shift.map(|_| shift(14)),
            lead_arm: v[17],
            lead_elbow: v[18],
            shaft_lean: self.shaft_lean.map(|_| v[19]),
            wrist_hinge: self.wrist_hinge.map(|_| v[20]),
        }
    }
}

/// One of the body metrics that can be measured alone ([`Body::value`]): the few advice
/// speaks of (see [`crate::checks`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Measure {
    /// The thorax's turn, degrees (the shoulders).
    ThoraxTurn,
    /// The pelvis's turn, degrees (the hips).
    PelvisTurn,
    /// The pelvis's sway toward the target, metres.
    PelvisSway,
    /// The pelvis's thrust toward the ball, metres.
    PelvisThrust,
    /// The head's lift, metres.
    HeadLift,
    /// The lead elbow's flexion, degrees.
    LeadElbow,
}

impl Measure {
    /// Every measure.
    pub const ALL: [Measure; 6] = [
        Measure::ThoraxTurn,
        Measure::PelvisTurn,
        Measure::PelvisSway,
        Measure::PelvisThrust,
        Measure::HeadLift,
        Measure::LeadElbow,
    ];

    /// The snake_case name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Measure::ThoraxTurn => "thorax_turn",
            Measure::PelvisTurn => "pelvis_turn",
            Measure::PelvisSway => "pelvis_sway",
            Measure::PelvisThrust => "pelvis_thrust",
            Measure::HeadLift => "head_lift",
            Measure::LeadElbow => "lead_elbow",
        }
    }

    /// Its value in `metrics`: degrees or metres ([`Measure::in_degrees`]); `None` for a head
    /// the skeleton lacks.
    pub fn of(self, metrics: &Metrics) -> Option<f32> {
        Some(match self {
            Measure::ThoraxTurn => metrics.thorax.turn,
            Measure::PelvisTurn => metrics.pelvis.turn,
            Measure::PelvisSway => metrics.pelvis_shift.sway,
            Measure::PelvisThrust => metrics.pelvis_shift.thrust,
            Measure::HeadLift => metrics.head_shift?.lift,
            Measure::LeadElbow => metrics.lead_elbow,
        })
    }

    /// Whether it is an angle (degrees) rather than a shift (metres).
    pub const fn in_degrees(self) -> bool {
        matches!(
            self,
            Measure::ThoraxTurn | Measure::PelvisTurn | Measure::LeadElbow
        )
    }
}

/// Why a skeleton's body metrics cannot be measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BodyError {
    /// The skeleton lacks a joint every metric needs.
    MissingJoint(Joint),
}

impl core::fmt::Display for BodyError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            BodyError::MissingJoint(j) => {
                write!(f, "body metrics need the {} joint", j.name())
            }
        }
    }
}

impl core::error::Error for BodyError {}

/// The joints a skeleton's body metrics are measured from, for one lead side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Body {
    /// The skeleton's joint count: the least a frame holds.
    joints: usize,
    /// Lead, trail.
    hips: [usize; 2],
    /// Lead, trail.
    shoulders: [usize; 2],
    pelvis: usize,
    /// The spine joint, where the skeleton has one.
    spine: Option<usize>,
    /// The thorax joint (else the neck), where the skeleton has one.
    thorax: Option<usize>,
    head: Option<usize>,
    /// Lead elbow, lead wrist.
    lead_arm: [usize; 2],
    /// Grip, club head.
    club: Option<[usize; 2]>,
}

impl Body {
    /// The joints of `skeleton` for a golfer whose lead side is `lead`.
    ///
    /// # Errors
    /// [`BodyError::MissingJoint`] when the skeleton lacks a hip, a shoulder, the lead elbow or
    /// wrist, or the pelvis.
    pub fn new(skeleton: &Skeleton, lead: Side) -> Result<Body, BodyError> {
        let need = |j: Joint| skeleton.index_of(j).ok_or(BodyError::MissingJoint(j));
        let pair = |left: Joint, right: Joint| -> Result<[usize; 2], BodyError> {
            let (l, r) = (need(left)?, need(right)?);
            Ok(match lead {
                Side::Left => [l, r],
                Side::Right => [r, l],
            })
        };
        let (elbow, wrist) = match lead {
            Side::Left => (Joint::LeftElbow, Joint::LeftWrist),
            Side::Right => (Joint::RightElbow, Joint::RightWrist),
        };
        let club = skeleton
            .index_of(Joint::ClubGrip)
            .zip(skeleton.index_of(Joint::ClubHead))
            .map(|(g, h)| [g, h]);
        Ok(Body {
            joints: skeleton.len(),
            hips: pair(Joint::LeftHip, Joint::RightHip)?,
            shoulders: pair(Joint::LeftShoulder, Joint::RightShoulder)?,
            pelvis: need(Joint::Pelvis)?,
            spine: skeleton.index_of(Joint::Spine),
            thorax: skeleton.find(&[Joint::Thorax, Joint::Neck]),
            head: skeleton.find(&[Joint::Head, Joint::HeadTop, Joint::Neck]),
            lead_arm: [need(elbow)?, need(wrist)?],
            club,
        })
    }

    /// The metrics of `frame`, its shifts counted from `address` (both frames of this
    /// skeleton's joints, in the same world frame as `stance`); `None` when either frame is
    /// shorter than the skeleton.
    pub fn measure(&self, stance: &Stance, address: &[Vec3], frame: &[Vec3]) -> Option<Metrics> {
        if address.len() < self.joints || frame.len() < self.joints {
            return None;
        }
        let shift = |k: &dyn Fn(&[Vec3]) -> Vec3| {
            let d = stance.direction(k(frame) - k(address));
            Shift {
                sway: d.x,
                thrust: d.y,
                lift: d.z,
            }
        };
        let hips = |f: &[Vec3]| self.between_hips(f);
        let local = |d: Vec3| stance.direction(d);
        let pelvis = angles(self.pelvis_axes(frame, local));
        let chest = self.thorax_axes(frame, local);
        let trunk = stance.direction(self.chest(frame) - hips(frame));
        let [elbow, wrist] = self.lead_arm.map(|k| frame[k]);
        let shoulder = frame[self.shoulders[0]];
        let club = self.club.map(|[g, h]| (frame[g], frame[h]));
        let thorax_angles = angles(chest);
        Some(Metrics {
            pelvis,
            thorax: thorax_angles,
            x_factor: thorax_angles.turn - pelvis.turn,
            spine: degrees(libm::atan2f(trunk.y, trunk.z)),
            pelvis_shift: shift(&hips),
            thorax_shift: shift(&|f: &[Vec3]| self.chest(f)),
            head_shift: self.head.map(|k| shift(&|f: &[Vec3]| f[k])),
            lead_arm: across(chest, stance.direction(wrist - shoulder)),
            lead_elbow: self.lead_elbow(frame),
            shaft_lean: club.map(|(grip, head)| {
                let shaft = stance.direction(grip - head);
                degrees(libm::atan2f(shaft.x, shaft.z))
            }),
            wrist_hinge: club.map(|(grip, head)| between(wrist - elbow, head - grip)),
        })
    }

    /// `measure` of `frame` alone, shifts counted from `address`: what [`Body::measure`] gives
    /// for it, to the bit, from only the joints [`Body::joints_of`] names; `None` where a
    /// frame is shorter than the skeleton or a head is measured that the skeleton lacks.
    pub fn value(
        &self,
        measure: Measure,
        stance: &Stance,
        address: &[Vec3],
        frame: &[Vec3],
    ) -> Option<f32> {
        if address.len() < self.joints || frame.len() < self.joints {
            return None;
        }
        let local = |d: Vec3| stance.direction(d);
        let hips = || local(self.between_hips(frame) - self.between_hips(address));
        Some(match measure {
            Measure::ThoraxTurn => turn(self.thorax_axes(frame, local)),
            Measure::PelvisTurn => turn(self.pelvis_axes(frame, local)),
            Measure::PelvisSway => hips().x,
            Measure::PelvisThrust => hips().y,
            Measure::HeadLift => self.head.map(|k| local(frame[k] - address[k]).z)?,
            Measure::LeadElbow => self.lead_elbow(frame),
        })
    }

    /// The joints `measure` is measured from: its value moves with these and no others.
    pub fn joints_of(&self, measure: Measure) -> heapless::Vec<usize, 5> {
        let [lead, trail] = self.shoulders;
        let chest = match self.thorax {
            Some(k) => [Some(k), None],
            None => [Some(lead), Some(trail)],
        };
        let joints: [Option<usize>; 5] = match measure {
            Measure::ThoraxTurn => [
                Some(lead),
                Some(trail),
                self.thorax,
                Some(self.spine.unwrap_or(self.pelvis)),
                None,
            ],
            Measure::PelvisTurn => [
                Some(self.hips[0]),
                Some(self.hips[1]),
                Some(self.pelvis),
                chest[0],
                chest[1],
            ],
            Measure::PelvisSway | Measure::PelvisThrust => {
                [Some(self.hips[0]), Some(self.hips[1]), None, None, None]
            }
            Measure::HeadLift => [self.head, None, None, None, None],
            Measure::LeadElbow => [
                Some(lead),
                Some(self.lead_arm[0]),
                Some(self.lead_arm[1]),
                None,
                None,
            ],
        };
        joints.into_iter().flatten().collect()
    }

    /// The joints `link`'s rotation ([`Body::speed`]) is measured from: a turn's for the pelvis
    /// and the thorax, the lead shoulder and wrist for the arm, grip and head for the club.
    pub fn joints_of_link(&self, link: Link) -> heapless::Vec<usize, 5> {
        match link {
            Link::Pelvis => self.joints_of(Measure::PelvisTurn),
            Link::Thorax => self.joints_of(Measure::ThoraxTurn),
            Link::LeadArm => [self.shoulders[0], self.lead_arm[1]].into_iter().collect(),
            Link::Club => self.club.into_iter().flatten().collect(),
        }
    }

    /// The pelvis's and the thorax's frames in `frame` (in whatever coordinates it is given;
    /// `None` when it is shorter than the skeleton): each an origin, the point between the hips
    /// and the thorax's point, and its axes (lateral toward the lead side, long, forward: unit vectors).
    pub fn segments(&self, frame: &[Vec3]) -> Option<[(Vec3, [Vec3; 3]); 2]> {
        if frame.len() < self.joints {
            return None;
        }
        let same = |d: Vec3| d;
        Some([
            (self.between_hips(frame), self.pelvis_axes(frame, same)),
            (self.chest(frame), self.thorax_axes(frame, same)),
        ])
    }

    /// The point between the hips (`frame` long enough).
    fn between_hips(&self, frame: &[Vec3]) -> Vec3 {
        (frame[self.hips[0]] + frame[self.hips[1]]) * 0.5
    }

    /// The lead elbow's flexion (`frame` long enough), degrees.
    fn lead_elbow(&self, frame: &[Vec3]) -> f32 {
        let [elbow, wrist] = self.lead_arm.map(|k| frame[k]);
        between(elbow - frame[self.shoulders[0]], wrist - elbow)
    }

    /// The thorax's point: its joint, else between the shoulders (`frame` long enough).
    fn chest(&self, frame: &[Vec3]) -> Vec3 {
        match self.thorax {
            Some(k) => frame[k],
            None => (frame[self.shoulders[0]] + frame[self.shoulders[1]]) * 0.5,
        }
    }

    /// The pelvis's [`axes`] in `frame` (long enough), its directions taken through `to`
    /// (into stance coordinates, or left as they are).
    fn pelvis_axes(&self, frame: &[Vec3], to: impl Fn(Vec3) -> Vec3) -> [Vec3; 3] {
        axes(
            to(frame[self.hips[0]] - frame[self.hips[1]]),
            to(self.chest(frame) - frame[self.pelvis]),
        )
    }

    /// The thorax's [`axes`] in `frame` (long enough), its directions taken through `to`.
    fn thorax_axes(&self, frame: &[Vec3], to: impl Fn(Vec3) -> Vec3) -> [Vec3; 3] {
        let lower = self.spine.map_or(frame[self.pelvis], |k| frame[k]);
        axes(
            to(frame[self.shoulders[0]] - frame[self.shoulders[1]]),
            to(self.chest(frame) - lower),
        )
    }

    /// How fast `link` turns at frame `t` of `swing` (frames × the skeleton's joints at `hz`, a
    /// positive rate), degrees per second: the angle it turns from `SMOOTHING_S / 2` before to
    /// as long after (see [`crate::sequence::kinematic_sequence`]). `None` within that of either end of the swing
    /// and for a club that is not tracked.
    pub fn speed(&self, link: Link, swing: Frames<'_>, hz: f32, t: usize) -> Option<f32> {
        let half = self.window(hz) / 2;
        let (a, b) = (t.checked_sub(half)?, t.checked_add(half)?);
        if b >= swing.len() || swing.joints() != self.joints {
            return None;
        }
        let (mut pose_a, mut pose_b) = ([Vec3::zeros(); MAX_JOINTS], [Vec3::zeros(); MAX_JOINTS]);
        let turned = self.turned(
            link,
            swing.frame(a, &mut pose_a),
            swing.frame(b, &mut pose_b),
        )?;
        Some(turned * hz / (2 * half) as f32)
    }

    /// How many frames at `hz` apart the two poses [`Body::speed`] compares are (even, at
    /// least 2).
    pub fn window(&self, hz: f32) -> usize {
        2 * (libm::roundf(0.5 * SMOOTHING_S * hz) as usize).max(1)
    }

    /// How far `link` turns from frame `a` to frame `b` (both long enough), degrees: the pelvis
    /// and the thorax about their own long axes (the turn of the lateral axis about the mean of
    /// the two frames' long axes, as a sensor on the segment reads its axial rotation), the
    /// lead arm (shoulder to wrist) and the shaft (grip to head) as directions (joint centres do
    /// not show a limb's twist about itself); `None` for a club that is not tracked.
    fn turned(&self, link: Link, a: &[Vec3], b: &[Vec3]) -> Option<f32> {
        let about_long_axis = |[la, ua, _]: [Vec3; 3], [lb, ub, _]: [Vec3; 3]| {
            let u = (ua + ub).try_normalize(1e-9).unwrap_or(ua);
            between(la - u * la.dot(&u), lb - u * lb.dot(&u))
        };
        // In the world's own coordinates: only the change between the two matters.
        let same = |d: Vec3| d;
        match link {
            Link::Pelvis => Some(about_long_axis(
                self.pelvis_axes(a, same),
                self.pelvis_axes(b, same),
            )),
            Link::Thorax => Some(about_long_axis(
                self.thorax_axes(a, same),
                self.thorax_axes(b, same),
            )),
            Link::LeadArm => {
                let arm = |f: &[Vec3]| f[self.lead_arm[1]] - f[self.shoulders[0]];
                Some(between(arm(a), arm(b)))
            }
            Link::Club => self.club.map(|[g, h]| between(a[h] - a[g], b[h] - b[g])),
        }
    }
}

/// A link of the kinematic sequence, in the order an efficient downswing peaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum Link {
    Pelvis,
    Thorax,
    LeadArm,
    Club,
}

impl Link {
    /// Every link, in the order an efficient downswing peaks.
    pub const ALL: [Link; 4] = [Link::Pelvis, Link::Thorax, Link::LeadArm, Link::Club];

    /// The snake_case name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Link::Pelvis => "pelvis",
            Link::Thorax => "thorax",
            Link::LeadArm => "lead_arm",
            Link::Club => "club",
        }
    }
}

/// A swing's metrics at each P-position it has, in [`Position::ALL`] order (`None` where it has
/// none): `swing` is frames × `skeleton` joints, `events` its events. Each pose is taken at its
/// position's time, between frames (a club head moves 30 cm in a frame at 120 Hz through
/// impact); the stance frame and the shifts are P1's.
///
/// # Errors
/// [`BodyError::MissingJoint`] as [`Body::new`].
pub fn at_positions(
    skeleton: &Skeleton,
    swing: Frames<'_>,
    events: &SwingEvents,
) -> Result<[Option<Metrics>; Position::ALL.len()], BodyError> {
    let mut table = [None; Position::ALL.len()];
    each_position(skeleton, swing, events, &mut |position, at| {
        table[position as usize] = at.metrics();
    })?;
    Ok(table)
}

/// How a swing's input may err: its noise per stance axis (toward the target, toward the
/// ball, up; metres, one standard deviation) and how early or late each P-position may have
/// been found (frames, one standard deviation, [`Position::ALL`] order).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InputError {
    /// Metres per stance axis.
    pub noise_m: [f32; 3],
    /// Frames per P-position.
    pub timing: [f32; Position::ALL.len()],
}

/// The uncertainty of each of [`at_positions`]'s metrics (one standard deviation, in the
/// metrics' own units; `None` where the swing has no such position), for input that errs by
/// `error`: each joint moved by the noise along each stance axis, at the position and at
/// address (at P1 the same pose, moved as one), and the position found early or late by its
/// timing's uncertainty.
///
/// # Errors
/// [`BodyError::MissingJoint`] as [`Body::new`].
pub fn spread_at_positions(
    skeleton: &Skeleton,
    swing: Frames<'_>,
    events: &SwingEvents,
    error: &InputError,
) -> Result<[Option<Metrics>; Position::ALL.len()], BodyError> {
    let mut table = [None; Position::ALL.len()];
    each_position(skeleton, swing, events, &mut |position, at| {
        table[position as usize] = at.spread(error, position);
    })?;
    Ok(table)
}

/// One P-position of a swing as [`each_position`] hands it over.
struct AtPosition<'a> {
    body: &'a Body,
    stance: &'a Stance,
    swing: Frames<'a>,
    /// Its time, frames.
    time: f32,
    address: [Vec3; MAX_JOINTS],
    at: [Vec3; MAX_JOINTS],
}

impl AtPosition<'_> {
    /// The metrics here.
    fn metrics(&self) -> Option<Metrics> {
        let n = self.body.joints;
        self.body
            .measure(self.stance, &self.address[..n], &self.at[..n])
    }

    /// The uncertainty of [`AtPosition::metrics`] for input that errs by `error` (see
    /// [`spread_at_positions`]); this position is `position`.
    fn spread(&mut self, error: &InputError, position: Position) -> Option<Metrics> {
        let here = self.metrics()?;
        let base = here.values();
        let mut variance = [0.0f32; VALUES];
        let mut add = |a: Option<Metrics>, b: [f32; VALUES], scale: f32| {
            if let Some(a) = a {
                for (v, (a, b)) in variance.iter_mut().zip(a.values().into_iter().zip(b)) {
                    *v += (scale * (a - b)) * (scale * (a - b));
                }
            }
        };
        let axes = [
            self.stance.toward_target(),
            self.stance.toward_ball(),
            Vec3::y(),
        ];
        // At P1 the two poses are one: they move together.
        let moved: &[&[bool]] = match position {
            Position::P1 => &[&[false, true]],
            _ => &[&[false], &[true]],
        };
        for k in 0..self.body.joints {
            for (direction, noise) in axes.iter().zip(error.noise_m) {
                let step = direction * noise;
                for poses in moved {
                    poses.iter().for_each(|&a| self.pose(a)[k] += step);
                    add(self.metrics(), base, 1.0);
                    poses.iter().for_each(|&a| self.pose(a)[k] -= step);
                }
            }
        }
        let h = error.timing[position as usize];
        if h > 0.0 {
            let (kept, time) = ((self.at, self.address), self.time);
            let tied = position == Position::P1;
            let mut at = |t: f32| {
                pose_at(self.swing, self.body.joints, t, &mut self.at)?;
                if tied {
                    self.address = self.at;
                }
                self.metrics()
            };
            let (later, earlier) = (at(time + h), at(time - h));
            (self.at, self.address) = kept;
            if let Some(earlier) = earlier {
                add(later, earlier.values(), 0.5);
            }
        }
        Some(here.with_values(variance.map(libm::sqrtf)))
    }

    /// The pose at address or at the position.
    fn pose(&mut self, address: bool) -> &mut [Vec3; MAX_JOINTS] {
        match address {
            true => &mut self.address,
            false => &mut self.at,
        }
    }
}

/// `visit` each P-position `swing` (frames × `skeleton` joints) has by its `events`, in
/// [`Position::ALL`] order, with its poses and stance.
///
/// # Errors
/// [`BodyError::MissingJoint`] as [`Body::new`].
fn each_position(
    skeleton: &Skeleton,
    swing: Frames<'_>,
    events: &SwingEvents,
    visit: &mut dyn FnMut(Position, &mut AtPosition<'_>),
) -> Result<(), BodyError> {
    let body = Body::new(skeleton, events.lead)?;
    let joints = body.joints.min(MAX_JOINTS);
    let mut address = [Vec3::zeros(); MAX_JOINTS];
    let Some(()) = events
        .time(Position::P1)
        .and_then(|t| pose_at(swing, joints, t, &mut address))
    else {
        return Ok(());
    };
    let stance = Stance::new(skeleton, &address[..joints], events.lead);
    for position in Position::ALL {
        let mut at = AtPosition {
            body: &body,
            stance: &stance,
            swing,
            time: 0.0,
            address,
            at: [Vec3::zeros(); MAX_JOINTS],
        };
        if let Some(time) = events.time(position) {
            if pose_at(swing, joints, time, &mut at.at).is_some() {
                at.time = time;
                visit(position, &mut at);
            }
        }
    }
    Ok(())
}

/// The pose of `swing` (frames × `joints`) at `time` (frames, clamped to the swing), linear
/// between the frames around it; `None` for an empty swing or one of other joints.
fn pose_at(
    swing: Frames<'_>,
    joints: usize,
    time: f32,
    out: &mut [Vec3; MAX_JOINTS],
) -> Option<()> {
    let last = swing.len().checked_sub(1)?;
    if swing.joints() != joints || joints > MAX_JOINTS {
        return None;
    }
    let time = time.clamp(0.0, last as f32);
    let (f, w) = (time as usize, time - libm::floorf(time));
    let g = (f + 1).min(last);
    for (k, o) in out.iter_mut().enumerate().take(joints) {
        *o = swing.at(f, k) * (1.0 - w) + swing.at(g, k) * w;
    }
    Some(())
}

/// A segment's axes in stance coordinates (toward the target, toward the ball, up): the unit
/// lateral axis along `lateral` (trail to lead), the long axis `long` made perpendicular to it,
/// and the forward axis `long × lateral`, out of the chest. Degenerate input gives the stance
/// frame's own axes.
fn axes(lateral: Vec3, long: Vec3) -> [Vec3; 3] {
    let l = lateral.try_normalize(1e-9).unwrap_or(Vec3::x());
    let u = (long - l * long.dot(&l))
        .try_normalize(1e-9)
        .unwrap_or(Vec3::z());
    [l, u, u.cross(&l)]
}

/// The turn, bend and side bend of a segment with these [`axes`]: the forward axis leans down
/// by the bend and faces away from the ball by the turn; the lateral axis rises against the
/// long one by the side bend.
fn angles([l, u, f]: [Vec3; 3]) -> Angles {
    Angles {
        turn: turn([l, u, f]),
        bend: degrees(libm::atan2f(-f.z, crate::math::hypot(f.x, f.y))),
        side_bend: degrees(libm::atan2f(l.z, u.z)),
    }
}

/// The turn of a segment with these [`axes`] (see [`angles`]).
fn turn([_, _, f]: [Vec3; 3]) -> f32 {
    degrees(libm::atan2f(-f.x, f.y))
}

/// The direction of `v` in the transverse plane of a segment with these [`axes`], from its
/// lateral axis toward its forward axis, degrees (0 to 180 in front of it, negative behind).
fn across([l, _, f]: [Vec3; 3], v: Vec3) -> f32 {
    degrees(libm::atan2f(v.dot(&f), v.dot(&l)))
}

/// The angle between `a` and `b`, degrees, 0 when they point the same way.
fn between(a: Vec3, b: Vec3) -> f32 {
    degrees(libm::atan2f(a.cross(&b).norm(), a.dot(&b)))
}

fn degrees(radians: f32) -> f32 {
    radians.to_degrees()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::format::Format;
    use crate::joint::JOINT_COUNT;
    use nalgebra::{Rotation3, Vector3};
    use proptest::strategy::Strategy;

    /// A segment's rotation in stance coordinates from its turn, bend and side bend (degrees),
    /// composed from axis-angle rotations, independently of [`angles`]: turn about up, then
    /// bend about the turned lateral axis, then side bend about the forward axis.
    fn rotation(a: Angles) -> Rotation3<f32> {
        let about = |axis: Vector3<f32>, deg: f32| {
            Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), deg.to_radians())
        };
        // Closing the turn takes the forward axis (+ball) toward −target: about +up. Bending
        // forward takes it down: about −lateral. Side bending to the trail side lifts the lead
        // side: about −forward.
        about(Vector3::z(), a.turn)
            * about(-Vector3::x(), a.bend)
            * about(-Vector3::y(), a.side_bend)
    }

    /// What a golfer's pose is made of, in stance coordinates.
    #[derive(Clone, Copy)]
    pub(crate) struct Posed {
        pub(crate) pelvis: Angles,
        pub(crate) thorax: Angles,
        /// Between the hips.
        pub(crate) centre: Vec3,
        /// Lead arm: across the chest and elbow flexion, degrees.
        pub(crate) arm: (f32, f32),
        /// The shaft about the lead forearm and its wrist hinge from it, degrees.
        pub(crate) club: (f32, f32),
    }

    const UPPER_ARM: f32 = 0.3;
    const FOREARM: f32 = 0.27;

    /// The joints of `skeleton` for `posed`, in stance coordinates (lead side +target).
    pub(crate) fn pose(skeleton: &Skeleton, lead: Side, posed: &Posed) -> [Vec3; 24] {
        let (rp, rt) = (rotation(posed.pelvis), rotation(posed.thorax));
        let pelvis = posed.centre;
        // The pelvis's long axis is the trunk, the thorax's from the spine joint up.
        let thorax = pelvis + rp * Vec3::new(0.0, 0.0, 0.45);
        let spine = thorax - rt * Vec3::new(0.0, 0.0, 0.3);
        let neck = thorax + rt * Vec3::new(0.0, 0.0, 0.1);
        let head = neck + rt * Vec3::new(0.0, 0.05, 0.12);
        let (lead_shoulder, trail_shoulder) = (
            thorax + rt * Vec3::new(0.18, 0.0, 0.0),
            thorax - rt * Vec3::new(0.18, 0.0, 0.0),
        );
        // The upper arm in the thorax's transverse plane at `across`; the forearm bent by the
        // flexion within that plane, toward the front.
        let (across, flexion) = posed.arm;
        let upper =
            rt * Rotation3::from_axis_angle(&Vector3::z_axis(), across.to_radians()) * Vec3::x();
        let fore = rt
            * Rotation3::from_axis_angle(&Vector3::z_axis(), (across + flexion).to_radians())
            * Vec3::x();
        let elbow = lead_shoulder + upper * UPPER_ARM;
        let wrist = elbow + fore * FOREARM;
        let (around, hinge) = posed.club;
        let grip = wrist;
        let club_head = grip + shaft(fore, around, hinge);
        let mut out = [Vec3::zeros(); 24];
        for (k, j) in skeleton.joints().iter().enumerate() {
            let side = |left: bool| (left == (lead == Side::Left)) as i32 as f32 * 2.0 - 1.0;
            let foot = |left: bool| Vec3::new(0.2 * side(left), 0.05, 0.08);
            out[k] = match j {
                Some(Joint::Pelvis) => pelvis,
                Some(Joint::LeftHip) => pelvis + rp * Vec3::new(0.12 * side(true), 0.0, 0.0),
                Some(Joint::RightHip) => pelvis + rp * Vec3::new(0.12 * side(false), 0.0, 0.0),
                Some(Joint::LeftKnee) => (pelvis + foot(true)) * 0.5,
                Some(Joint::RightKnee) => (pelvis + foot(false)) * 0.5,
                Some(Joint::LeftAnkle) => foot(true),
                Some(Joint::RightAnkle) => foot(false),
                Some(Joint::LeftToe) => foot(true) + Vec3::new(0.0, 0.15, -0.05),
                Some(Joint::RightToe) => foot(false) + Vec3::new(0.0, 0.15, -0.05),
                Some(Joint::Spine) => spine,
                Some(Joint::Thorax) => thorax,
                Some(Joint::Neck) => neck,
                Some(Joint::Head) => head,
                Some(Joint::HeadTop) => head + rt * Vec3::new(0.0, 0.0, 0.1),
                Some(j @ (Joint::LeftShoulder | Joint::RightShoulder)) => {
                    if side(*j == Joint::LeftShoulder) > 0.0 {
                        lead_shoulder
                    } else {
                        trail_shoulder
                    }
                }
                Some(j @ (Joint::LeftElbow | Joint::RightElbow)) => {
                    if side(*j == Joint::LeftElbow) > 0.0 {
                        elbow
                    } else {
                        trail_shoulder + Vec3::new(0.0, 0.1, -0.3)
                    }
                }
                Some(j @ (Joint::LeftWrist | Joint::RightWrist)) => {
                    if side(*j == Joint::LeftWrist) > 0.0 {
                        wrist
                    } else {
                        trail_shoulder + Vec3::new(0.05, 0.15, -0.55)
                    }
                }
                Some(Joint::ClubGrip) => grip,
                Some(Joint::ClubHead) => club_head,
                _ => pelvis,
            };
        }
        out
    }

    /// The unit shaft direction (grip to head) at `hinge` degrees from `fore`, at `around`
    /// degrees about it.
    fn shaft(fore: Vec3, around: f32, hinge: f32) -> Vec3 {
        let f = fore.normalize();
        let a = f.cross(&Vec3::z()).try_normalize(1e-6).unwrap_or(Vec3::x());
        let b = f.cross(&a);
        let (h, phi) = (hinge.to_radians(), around.to_radians());
        f * libm::cosf(h) + (a * libm::cosf(phi) + b * libm::sinf(phi)) * libm::sinf(h)
    }

    /// Stance coordinates to a world frame: `up` is +Y, the target line turned `heading`
    /// degrees about it, mirrored across the vertical plane of +Y and +Z when `mirror`, and
    /// moved by `by`.
    pub(crate) fn world(p: Vec3, heading: f32, mirror: bool, by: Vec3) -> Vec3 {
        let v = Vec3::new(if mirror { -p.x } else { p.x }, p.z, p.y);
        Rotation3::from_axis_angle(&Vector3::y_axis(), heading.to_radians()) * v + by
    }

    fn close(a: f32, b: f32, tolerance: f32) -> bool {
        (a - b).abs() <= tolerance
    }

    pub(crate) const ADDRESS: Posed = Posed {
        pelvis: Angles {
            turn: -3.0,
            bend: 20.0,
            side_bend: 4.0,
        },
        thorax: Angles {
            turn: 2.0,
            bend: 40.0,
            side_bend: 12.0,
        },
        centre: Vec3::new(0.0, -0.05, 0.95),
        arm: (100.0, 5.0),
        club: (200.0, 35.0),
    };

    const TOP: Posed = Posed {
        pelvis: Angles {
            turn: 48.0,
            bend: 22.0,
            side_bend: -8.0,
        },
        thorax: Angles {
            turn: 92.0,
            bend: 33.0,
            side_bend: -25.0,
        },
        centre: Vec3::new(-0.04, 0.02, 0.97),
        arm: (150.0, 20.0),
        club: (40.0, 90.0),
    };

    /// Measures `posed` against `address` for `skeleton`, placed in the world by `heading`,
    /// `mirror` and `by`.
    fn measured(format: Format, lead: Side, heading: f32, mirror: bool, posed: &Posed) -> Metrics {
        let skeleton = Skeleton::standard(format).unwrap();
        let by = Vec3::new(1.5, 0.0, -2.0);
        let place = |p: &Posed| pose(&skeleton, lead, p).map(|v| world(v, heading, mirror, by));
        let (address, frame) = (place(&ADDRESS), place(posed));
        let n = skeleton.len();
        let stance = Stance::new(&skeleton, &address[..n], lead);
        Body::new(&skeleton, lead)
            .unwrap()
            .measure(&stance, &address[..n], &frame[..n])
            .unwrap()
    }

    #[test]
    fn posed_angles_are_measured_back() {
        let placed = [
            (0.0, false, Side::Left),
            (137.0, false, Side::Left),
            (-61.0, true, Side::Right),
            (200.0, true, Side::Left),
        ];
        // Under Miri, which takes seconds over each pose, every other: a right-handed golfer
        // and a left-handed one, mirrored.
        for &(heading, mirror, lead) in placed.iter().step_by(if cfg!(miri) { 2 } else { 1 }) {
            for posed in [ADDRESS, TOP] {
                let m = measured(Format::GolfMarkers, lead, heading, mirror, &posed);
                let angles = |a: Angles, b: Angles| {
                    close(a.turn, b.turn, 0.01)
                        && close(a.bend, b.bend, 0.01)
                        && close(a.side_bend, b.side_bend, 0.01)
                };
                assert!(angles(m.pelvis, posed.pelvis), "{heading} {mirror}: {m:?}");
                assert!(angles(m.thorax, posed.thorax), "{heading} {mirror}: {m:?}");
                assert!(close(
                    m.x_factor,
                    posed.thorax.turn - posed.pelvis.turn,
                    0.02
                ));
                let shift = posed.centre - ADDRESS.centre;
                let s = m.pelvis_shift;
                assert!(close(s.sway, shift.x, 1e-4) && close(s.thrust, shift.y, 1e-4));
                assert!(close(s.lift, shift.z, 1e-4), "{m:?}");
                let thorax = |p: &Posed| p.centre + rotation(p.pelvis) * Vec3::new(0.0, 0.0, 0.45);
                let moved = thorax(&posed) - thorax(&ADDRESS);
                let t = m.thorax_shift;
                let got = Vec3::new(t.sway, t.thrust, t.lift);
                assert!((got - moved).norm() < 1e-4, "{m:?}");
                let (across, flexion) = posed.arm;
                let (l1, l2, k) = (UPPER_ARM, FOREARM, flexion.to_radians());
                let expected =
                    across + degrees(libm::atan2f(l2 * libm::sinf(k), l1 + l2 * libm::cosf(k)));
                assert!(close(m.lead_arm, expected, 0.02), "{m:?}");
                assert!(close(m.lead_elbow, flexion, 0.05), "{m:?}");
                let (around, hinge) = posed.club;
                let skeleton = Skeleton::standard(Format::GolfMarkers).unwrap();
                let at = pose(&skeleton, lead, &posed);
                let joint = |left, right| {
                    at[skeleton
                        .index_of(if lead == Side::Left { left } else { right })
                        .unwrap()]
                };
                let fore = joint(Joint::LeftWrist, Joint::RightWrist)
                    - joint(Joint::LeftElbow, Joint::RightElbow);
                let grip_up = -shaft(fore, around, hinge);
                let lean = degrees(libm::atan2f(grip_up.x, grip_up.z));
                assert!(close(m.shaft_lean.unwrap(), lean, 0.05), "{m:?}");
                assert!(close(m.wrist_hinge.unwrap(), hinge, 0.05), "{m:?}");
            }
        }
    }

    fn segment() -> impl proptest::strategy::Strategy<Value = Angles> {
        (-150.0f32..150.0, -70.0f32..70.0, -45.0f32..45.0).prop_map(|(turn, bend, side_bend)| {
            Angles {
                turn,
                bend,
                side_bend,
            }
        })
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 256 }))]
        #[test]
        fn any_posed_segment_is_measured_back(
            pelvis in segment(), thorax in segment(), heading in -180.0f32..180.0,
            mirror in proptest::bool::ANY,
        ) {
            let posed = Posed { pelvis, thorax, ..TOP };
            let m = measured(Format::GolfMarkers, Side::Left, heading, mirror, &posed);
            for (got, want) in [(m.pelvis, pelvis), (m.thorax, thorax)] {
                proptest::prop_assert!(close(got.turn, want.turn, 0.05), "{got:?} {want:?}");
                proptest::prop_assert!(close(got.bend, want.bend, 0.05), "{got:?} {want:?}");
                proptest::prop_assert!(close(got.side_bend, want.side_bend, 0.05), "{got:?} {want:?}");
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 256 }))]
        /// A measure alone is the full measurement's, to the bit, and moves with no joint but
        /// those it names.
        #[test]
        fn a_measure_alone_is_the_metrics_own_from_its_own_joints(
            pelvis in segment(), thorax in segment(), heading in -180.0f32..180.0,
            lead_left in proptest::bool::ANY, joint in 0usize..24, step in 0.01f32..0.1,
            bare in proptest::bool::ANY,
        ) {
            let lead = if lead_left { Side::Left } else { Side::Right };
            // With a spine joint, or without (the thorax's long axis from the pelvis).
            let format = if bare { Format::Coco17 } else { Format::GolfMarkers };
            let skeleton = Skeleton::standard(format).unwrap();
            proptest::prop_assert_eq!(skeleton.index_of(Joint::Spine).is_none(), bare);
            let n = skeleton.len();
            let by = Vec3::new(1.5, 0.0, -2.0);
            let place = |p: &Posed| pose(&skeleton, lead, p).map(|v| world(v, heading, false, by));
            let (address, mut frame) = (place(&ADDRESS), place(&Posed { pelvis, thorax, ..TOP }));
            let stance = Stance::new(&skeleton, &address[..n], lead);
            let body = Body::new(&skeleton, lead).unwrap();
            let metrics = body.measure(&stance, &address[..n], &frame[..n]).unwrap();
            let k = joint % n;
            let before = Measure::ALL.map(|m| body.value(m, &stance, &address[..n], &frame[..n]));
            frame[k] += stance.toward_target() * step + stance.toward_ball() * (0.7 * step)
                + Vec3::y() * (1.3 * step);
            for (m, was) in Measure::ALL.into_iter().zip(before) {
                proptest::prop_assert_eq!(was, m.of(&metrics), "{:?}", m);
                let now = body.value(m, &stance, &address[..n], &frame[..n]);
                // (A named joint may leave it unmoved in a special pose: the pelvis joint
                // tilts the long axis of an upright pelvis, which does not turn it.)
                proptest::prop_assert!(now == was || body.joints_of(m).contains(&k), "{:?} {}", m, k);
            }
        }
    }

    #[test]
    fn the_spine_angle_is_the_trunks_lean_seen_down_the_line() {
        let bent = Posed {
            pelvis: Angles {
                turn: 0.0,
                bend: 35.0,
                side_bend: 0.0,
            },
            thorax: Angles {
                turn: 60.0,
                bend: 10.0,
                side_bend: -20.0,
            },
            ..ADDRESS
        };
        let m = measured(Format::GolfMarkers, Side::Left, 30.0, false, &bent);
        assert!(close(m.spine, 35.0, 0.01), "{m:?}");
        // Turned 60° away, the same lean is seen shorter down the line: tan⁻¹(tan 35° cos 60°).
        let turned = Posed {
            pelvis: Angles {
                turn: 60.0,
                bend: 35.0,
                side_bend: 0.0,
            },
            ..bent
        };
        let m = measured(Format::GolfMarkers, Side::Left, 30.0, false, &turned);
        let seen = degrees(libm::atanf(libm::tanf(35f32.to_radians()) * 0.5));
        assert!(close(m.spine, seen, 0.01), "{m:?}");
    }

    #[test]
    fn a_skeleton_without_a_spine_joint_turns_with_its_trunk() {
        // COCO: the pelvis and thorax are midpoints, the thorax's long axis the whole trunk.
        let turned = Posed {
            pelvis: Angles {
                turn: 40.0,
                bend: 0.0,
                side_bend: 0.0,
            },
            thorax: Angles {
                turn: 85.0,
                bend: 0.0,
                side_bend: 0.0,
            },
            ..ADDRESS
        };
        let m = measured(Format::Coco17, Side::Left, 75.0, false, &turned);
        assert!(
            close(m.pelvis.turn, 40.0, 0.01) && close(m.thorax.turn, 85.0, 0.01),
            "{m:?}"
        );
        assert!(close(m.x_factor, 45.0, 0.02) && m.shaft_lean.is_none());
    }

    #[test]
    fn a_skeleton_without_hips_is_refused() {
        let h36m = Skeleton::standard(Format::H36m17).unwrap();
        assert!(Body::new(&h36m, Side::Right).is_ok());
        // The canonical body without the right hip (its knee hangs from the pelvis).
        let mut joints = [Joint::Pelvis; JOINT_COUNT];
        let mut rest = [Vec3::zeros(); JOINT_COUNT];
        let body = Joint::ALL
            .into_iter()
            .filter(|j| !j.is_club() && *j != Joint::RightHip);
        let mut n = 0;
        for (k, j) in body.enumerate() {
            (joints[k], rest[k], n) = (j, crate::format::t_pose(j), k + 1);
        }
        let skeleton = Skeleton::canonical(&joints[..n], &rest[..n]).unwrap();
        let refused = Err(BodyError::MissingJoint(Joint::RightHip));
        assert_eq!(Body::new(&skeleton, Side::Left), refused);
        assert_eq!(Body::new(&skeleton, Side::Right), refused);
    }

    #[test]
    #[cfg_attr(
        miri,
        ignore = "thousands of poses measured: minutes under Miri, no unsafe code"
    )]
    fn the_spread_of_a_shift_is_the_noise_and_of_a_turn_its_rate_times_the_timing() {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        // The pelvis turns half a degree a frame, all else held at address; seen 30° off.
        let mut frames = std::vec::Vec::new();
        for f in 0..100 {
            let mut posed = ADDRESS;
            posed.pelvis.turn += 0.5 * f as f32;
            let pose = pose(&skeleton, Side::Left, &posed);
            frames.extend(
                pose[..17]
                    .iter()
                    .map(|&p| world(p, 30.0, false, Vec3::zeros())),
            );
        }
        let swing = Frames::metres(&frames, 17);
        let mut times = [None; 10];
        for (e, f) in crate::events::Event::ALL
            .into_iter()
            .zip([10, 20, 30, 40, 50, 60, 70, 90])
        {
            times[Position::from(e) as usize] = Some(f as f32);
        }
        let events = SwingEvents::at_times(Side::Left, times);
        let spread = |noise_m, timing| {
            let error = InputError { noise_m, timing };
            spread_at_positions(&skeleton, swing, &events, &error).unwrap()[Position::P4 as usize]
                .unwrap()
        };
        // Each hip moved by the noise at the top and at address: the point between them by
        // the noise.
        let noisy = spread([0.01, 0.02, 0.005], [0.0; 10]);
        let s = noisy.pelvis_shift;
        assert!(
            close(s.sway, 0.01, 1e-4) && close(s.thrust, 0.02, 1e-4),
            "{s:?}"
        );
        assert!(close(s.lift, 0.005, 1e-4), "{s:?}");
        // The head, one joint: √2 the noise.
        let lift = noisy.head_shift.unwrap().lift;
        assert!(
            close(lift, 0.005 * core::f32::consts::SQRT_2, 1e-4),
            "{lift}"
        );
        // Found two frames early or late: the turn by a degree, the hips where they were.
        let late = spread([0.0; 3], [2.0; 10]);
        assert!(close(late.pelvis.turn, 1.0, 0.02), "{:?}", late.pelvis);
        assert!(late.pelvis_shift.sway < 1e-5, "{:?}", late.pelvis_shift);
        // Without noise or timing, no spread; at every position the swing has.
        let none = spread_at_positions(
            &skeleton,
            swing,
            &events,
            &InputError {
                noise_m: [0.0; 3],
                timing: [0.0; 10],
            },
        )
        .unwrap();
        let exact = at_positions(&skeleton, swing, &events).unwrap();
        for (s, m) in none.iter().zip(exact) {
            assert_eq!(s.is_some(), m.is_some());
            assert!(s.is_none_or(|s| s.values().iter().all(|v| v.is_nan() || *v == 0.0)));
        }
    }
}
