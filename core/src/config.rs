//! Capacity constants shared across modules: the limits that more than one module (or the wire
//! and the report it carries) must agree on.
//!
//! A limit that only one module uses lives beside it (`dtw::MAX_ANCHORS`, `wire::MAX_FRAME`,
//! `weights::MAX_HEADER`, ...); `docs/ARCHITECTURE.md` lists them all, and the README's
//! "Configuration" section gives each one's RAM cost.

/// Most joints one skeleton may have (BlazePose-33 landmarks and CMU-31 fit).
pub const MAX_JOINTS: usize = 40;

/// Longest swing, in frames, that can be scored (4.2 s at 60 Hz, 8.5 s at 30 Hz).
pub const MAX_SWING_FRAMES: usize = 256;

/// Joint deviations a report keeps per swing event, largest first.
pub const DEVIATIONS_PER_EVENT: usize = 3;

/// Most deviations a report holds, and a `SwingReport` carries (every one of the 8 events,
/// `events::Event::COUNT`, which checks it).
pub const MAX_DEVIATIONS: usize = 8 * DEVIATIONS_PER_EVENT;

/// Most body checks a report holds, and a `SwingReport` carries (one of each of
/// `checks::CHECKS`, whose array type is this long).
pub const MAX_CHECKS: usize = 9;

/// Most gaps of the kinematic sequence a report holds, and a `SwingReport` carries (one of
/// each of `sequence::GAPS`, whose array type is this long).
pub const MAX_GAPS: usize = 2;

/// Most advice items a report holds, and a `SessionReport` carries as tendencies.
pub const MAX_ADVICE: usize = 8;

/// The body-level quantities a range session keeps, and a `SessionReport` carries: the three
/// phases, the pause, one of each of the checks and one of each of the gaps
/// (`session::Quantity::BODY_LEVEL` lists them).
pub const BODY_LEVEL: usize = 3 + 1 + MAX_CHECKS + MAX_GAPS;

/// Set-aside swings a range session remembers (the latest), and a `SessionReport` carries.
pub const MAX_SET_ASIDE: usize = 8;
