//! The band of the dynamic time warping ([`crate::dtw`]): which cells of the frame matrix an
//! alignment may pass through.
//!
//! A band is a radius, in frames of the second swing, either side of a guide line through the
//! matrix: the diagonal from the first frames to the last, or, anchored, a diagonal per phase
//! between the matched swing events. It is only that setting and imports nothing, so the wire's
//! `Config` carries it without reaching the DTW; [`crate::dtw::Window`] lays it over one pair
//! of sequences.

/// The DTW band: `radius` columns either side of a guide line that runs through the matched
/// swing events, one diagonal per phase (`anchored`), or along the whole diagonal. One setting
/// from `posecoach score --band R [--global-band]` and the wire's `Config` to
/// [`Window::new`](crate::dtw::Window::new).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Band {
    /// Columns (frames of the second sequence) either side of the guide.
    pub radius: u16,
    /// The guide runs through anchors (swing events) rather than along the diagonal.
    pub anchored: bool,
}

impl Band {
    /// The default: 10 frames either side of the event-anchored guide (±0.17 s at 60 Hz).
    pub const DEFAULT: Band = Band {
        radius: 10,
        anchored: true,
    };

    /// A band of `radius` columns around the diagonal.
    pub const fn global(radius: u16) -> Band {
        Band {
            radius,
            anchored: false,
        }
    }
}
