//! One quantity's running statistics over a session's swings, in eight bytes, and the estimate
//! they give.
//!
//! A session sees each quantity once a swing (a phase's tempo, a body check, a joint's offset
//! along one axis at one event), each time with the swing's own stated uncertainty `u` (one
//! standard deviation). The golfer also varies from swing to swing. A [`Tally`] keeps, in the
//! quantity's own fixed-point unit:
//!
//! - the **mean** of the accepted values, each swing counted once;
//! - their sample standard deviation (the **spread**): measurement noise and the golfer's
//!   variation together, which is what the mean's uncertainty must be built from;
//! - the root mean square of the stated uncertainties (the **noise**), so that the golfer's
//!   own variation can be given net of it: `τ² = max(0, spread² − noise²)` (the method of
//!   moments' random-effects variance);
//! - how many values lay past the quantity's tolerance on each side (the evidence a golfer
//!   reads: "slow in 8 of 10 swings").
//!
//! The estimate's uncertainty is `√(max(spread², noise²) / n)`: the swings' own scatter, never
//! below what the stated noise alone allows with few swings. Its interval takes Student's `t`
//! for `n − 1` degrees of freedom ([`t95`]), as a scatter estimated from few swings must.
//!
//! **Robustness** (a half swing, a mishit, a lost track): from the third value on, a value is
//! pulled in to [`CLAMP`] predictive standard deviations of the running mean before it is
//! counted (winsorized), never closer than the quantity's tolerance. The first two values
//! cannot be judged against anything, but they can be recovered: two values are exactly
//! `mean ± spread / √2`, so at the third the tally is rebuilt from all three about their
//! median, each pulled in to [`CLAMP`] robust scales of it (the median absolute deviation,
//! never below the stated noise) or the tolerance, whichever is farther. One outlier among the
//! first three therefore moves the estimate by at most that much. Equal weights, not
//! inverse-variance ones: within a session the stated uncertainties differ little (one camera
//! or one set of sensors, one golfer), and a swing whose values lie far from the session's is
//! set aside whole by the session ([`crate::session`]).

/// A value more than this many predictive standard deviations from the running mean is pulled
/// in to it before it is counted.
pub const CLAMP: f32 = 3.5;

/// Running statistics of one quantity, in its fixed-point unit (see the caller's scale).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tally {
    /// Values counted, to 255: later values are not counted.
    n: u8,
    /// Values past the tolerance above.
    above: u8,
    /// Values past the tolerance below.
    below: u8,
    /// The mean, units.
    mean: i16,
    /// The sample standard deviation, units.
    spread: u16,
    /// The root mean square of the stated uncertainties, [`NOISE_STEP`] units.
    noise: u8,
}

/// A tally keeps its noise in steps of this many units (to 255 steps): the stated noise needs
/// less precision than the mean, and a byte less makes a 17-joint skeleton's tallies 0.8 KiB
/// smaller.
pub const NOISE_STEP: f32 = 8.0;

/// What a [`Tally`] says of its quantity, in the quantity's own unit (a [`Tally`]'s units
/// times the caller's scale).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Estimate {
    /// Swings counted.
    pub n: u8,
    /// The mean.
    pub value: f32,
    /// Its uncertainty (one standard deviation).
    pub uncertainty: f32,
    /// The swing-to-swing spread net of the stated noise (`τ`): how consistent the golfer is.
    pub spread: f32,
    /// The root mean square of the swings' stated uncertainties.
    pub noise: f32,
    /// Swings past the tolerance above.
    pub above: u8,
    /// Swings past the tolerance below.
    pub below: u8,
}

impl Estimate {
    /// Half the one-sided 95 % interval's width: `t95(n − 1)` times the uncertainty (infinite
    /// with fewer than two swings).
    pub fn margin(&self) -> f32 {
        t95(usize::from(self.n).saturating_sub(1)) * self.uncertainty
    }

    /// Whether the one-sided 95 % interval lies wholly past `tolerance` from zero.
    pub fn clears(&self, tolerance: f32) -> bool {
        libm::fabsf(self.value) - self.margin() > tolerance
    }

    /// Whether the one-sided 95 % interval lies wholly within `tolerance` of zero.
    pub fn within(&self, tolerance: f32) -> bool {
        libm::fabsf(self.value) + self.margin() < tolerance
    }

    /// About how many swings in all would settle whether the value is past `tolerance` (its
    /// interval wholly past it or wholly within it), if the mean and the scatter stay as they
    /// are: `(t · σ / | |value| − tolerance |)²`, at least one more than counted; `None` where
    /// nothing is known of the scatter yet or the value sits on the tolerance.
    pub fn swings_to_settle(&self, tolerance: f32) -> Option<u32> {
        let gap = libm::fabsf(libm::fabsf(self.value) - tolerance);
        let sigma = self.uncertainty * crate::math::sqrt(f32::from(self.n));
        if self.n < 2 || gap <= 0.0 || !sigma.is_finite() {
            return None;
        }
        // t at the swings needed, taken at the normal's 1.65 (a few swings' more t matters
        // little to a rough count).
        let needed = libm::ceilf((T95_LIMIT * sigma / gap) * (T95_LIMIT * sigma / gap));
        Some((needed.min(1e6) as u32).max(u32::from(self.n) + 1))
    }
}

/// The one-sided 95 % quantile of Student's `t` for large degrees of freedom.
pub const T95_LIMIT: f32 = 1.645;

/// The one-sided 95 % quantile of Student's `t` with `df` degrees of freedom (infinite at 0).
pub fn t95(df: usize) -> f32 {
    const TABLE: [f32; 30] = [
        6.314, 2.920, 2.353, 2.132, 2.015, 1.943, 1.895, 1.860, 1.833, 1.812, 1.796, 1.782, 1.771,
        1.761, 1.753, 1.746, 1.740, 1.734, 1.729, 1.725, 1.721, 1.717, 1.714, 1.711, 1.708, 1.706,
        1.703, 1.701, 1.699, 1.697,
    ];
    match df {
        0 => f32::INFINITY,
        // Past the table, t's excess over the normal quantile falls as 1/df.
        df => TABLE
            .get(df - 1)
            .copied()
            .unwrap_or(T95_LIMIT + (1.697 - T95_LIMIT) * 30.0 / df as f32),
    }
}

/// How far from the centre a value may lie before it is pulled in: [`CLAMP`] times `scale`,
/// never within `tolerance` (a difference advice would not act on is no outlier).
fn reach(scale: f32, tolerance: f32) -> f32 {
    (CLAMP * scale).max(tolerance)
}

/// `v` in units, saturating at what `i16` holds (NaN to 0).
fn to_units(v: f32) -> i16 {
    libm::roundf(v).clamp(f32::from(i16::MIN), f32::from(i16::MAX)) as i16
}

/// A non-negative `v` in units, saturating at what `u16` holds.
fn to_units_u(v: f32) -> u16 {
    libm::roundf(v).clamp(0.0, f32::from(u16::MAX)) as u16
}

impl Tally {
    /// No values.
    pub const EMPTY: Tally = Tally {
        n: 0,
        above: 0,
        below: 0,
        mean: 0,
        spread: 0,
        noise: 0,
    };

    /// Whether `value` (units) lies farther from the mean than a value is let lie before it
    /// is pulled in (quantity's `tolerance`, units): never with fewer than three values.
    pub fn unlike(&self, value: f32, tolerance: f32) -> bool {
        self.n >= 3
            && libm::fabsf(value - f32::from(self.mean)) > reach(self.predictive(), tolerance)
    }

    /// Counts `value` with its stated uncertainty `u` (both in units; `u` non-negative),
    /// counting it past `tolerance` (units) above or below where it is. A value that is not
    /// finite is not counted, nor any past the 255th.
    pub fn add(&mut self, value: f32, u: f32, tolerance: f32) {
        if !value.is_finite() || !u.is_finite() || self.n == u8::MAX {
            return;
        }
        let u = libm::fabsf(u);
        match self.n {
            2 => self.rebuild(value, u, tolerance),
            0 | 1 => self.push(value, u),
            _ => {
                let (mean, reach) = (f32::from(self.mean), reach(self.predictive(), tolerance));
                self.push(value.clamp(mean - reach, mean + reach), u);
            }
        }
        // The evidence counts what the swing showed, pulled in or not.
        self.above = self.above.saturating_add(u8::from(value > tolerance));
        self.below = self.below.saturating_add(u8::from(value < -tolerance));
    }

    /// The standard deviation of a new value about the running mean: the per-swing scatter
    /// (never below the stated noise) and the mean's own uncertainty.
    fn predictive(&self) -> f32 {
        let n = f32::from(self.n);
        let per_swing = f32::from(self.spread).max(self.noise());
        per_swing * crate::math::sqrt(1.0 + 1.0 / n)
    }

    /// Welford's update of the mean, the spread and the noise with `value`.
    fn push(&mut self, value: f32, u: f32) {
        let n = f32::from(self.n);
        let (mean, spread) = (f32::from(self.mean), f32::from(self.spread));
        let m2 = spread * spread * (n - 1.0).max(0.0);
        let next = mean + (value - mean) / (n + 1.0);
        let m2 = m2 + (value - mean) * (value - next);
        let noise = self.noise();
        let rms = crate::math::sqrt((noise * noise * n + u * u) / (n + 1.0));
        self.noise = libm::roundf(rms / NOISE_STEP).clamp(0.0, 255.0) as u8;
        self.mean = to_units(next);
        self.spread = match self.n {
            0 => 0,
            _ => to_units_u(crate::math::sqrt(m2.max(0.0) / n)),
        };
        self.n += 1;
    }

    /// The third value: the first two recovered (`mean ± spread / √2`), all three pulled in to
    /// [`CLAMP`] robust scales of their median, and counted afresh.
    fn rebuild(&mut self, value: f32, u: f32, tolerance: f32) {
        let (mean, half) = (
            f32::from(self.mean),
            f32::from(self.spread) * core::f32::consts::FRAC_1_SQRT_2,
        );
        let noise = self.noise();
        let mut values = [mean - half, mean + half, value];
        let mut sorted = values;
        sorted.sort_unstable_by(f32::total_cmp);
        let median = sorted[1];
        // The median absolute deviation of three values: the smaller of the outer two's.
        let mad = libm::fabsf(sorted[0] - median).min(libm::fabsf(sorted[2] - median));
        let noise_all = crate::math::sqrt((2.0 * noise * noise + u * u) / 3.0);
        let reach = reach((1.4826 * mad).max(noise_all), tolerance);
        for v in &mut values {
            *v = v.clamp(median - reach, median + reach);
        }
        let (above, below) = (self.above, self.below);
        *self = Tally {
            above,
            below,
            ..Tally::default()
        };
        self.push(values[0], noise);
        self.push(values[1], noise);
        self.push(values[2], u);
    }

    /// The estimate, each statistic times `scale` (the unit's size in the quantity's own unit).
    pub fn estimate(&self, scale: f32) -> Estimate {
        let n = f32::from(self.n);
        let (spread, noise) = (f32::from(self.spread), self.noise());
        let per_swing = spread.max(noise);
        Estimate {
            n: self.n,
            value: self.mean(scale),
            uncertainty: match self.n {
                0 => f32::INFINITY,
                _ => per_swing / crate::math::sqrt(n) * scale,
            },
            spread: crate::math::sqrt((spread * spread - noise * noise).max(0.0)) * scale,
            noise: noise * scale,
            above: self.above,
            below: self.below,
        }
    }

    /// The mean, times `scale` (as [`Self::estimate`] gives it).
    pub fn mean(&self, scale: f32) -> f32 {
        f32::from(self.mean) * scale
    }

    /// The root mean square of the stated uncertainties, units.
    fn noise(&self) -> f32 {
        f32::from(self.noise) * NOISE_STEP
    }

    /// Values counted.
    pub fn n(&self) -> u8 {
        self.n
    }

    /// How far `value` (units) lies from the running mean, in predictive standard deviations
    /// (0 with fewer than three values counted: nothing to judge it against).
    pub fn z(&self, value: f32) -> f32 {
        let scale = self.predictive();
        match self.n < 3 || scale <= 0.0 {
            true => 0.0,
            false => (value - f32::from(self.mean)) / scale,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{t95, Tally, CLAMP};
    use proptest::prelude::*;

    /// The batch mean and sample standard deviation of `values`.
    fn batch(values: &[f32]) -> (f32, f32) {
        let n = values.len() as f32;
        let mean = values.iter().sum::<f32>() / n;
        let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / (n - 1.0);
        (mean, var.sqrt())
    }

    proptest! {
        #[test]
        fn without_outliers_a_tally_is_the_batch_mean_and_spread(
            values in proptest::collection::vec(-3000.0f32..3000.0, 3..40),
        ) {
            // Values within a few spreads of each other are never pulled in (a wide stated
            // noise makes every value plausible).
            let mut tally = Tally::default();
            for v in &values {
                tally.add(*v, 3000.0, 1000.0);
            }
            let (mean, spread) = batch(&values);
            let e = tally.estimate(1.0);
            prop_assert_eq!(usize::from(e.n), values.len());
            // Each update rounds the mean and the spread to a unit: at most half a unit each
            // time, shrunk by n / (n + 1) at the next, so at most (n + 1) / 4 after n updates.
            let n = values.len() as f32;
            prop_assert!((e.value - mean).abs() <= 0.5 + (n + 1.0) / 4.0, "{} {}", e.value, mean);
            prop_assert!((tally.spread as f32 - spread).abs() <= 1.0 + n / 4.0 + 0.01 * spread);
            let above = values.iter().filter(|v| **v > 1000.0).count();
            let below = values.iter().filter(|v| **v < -1000.0).count();
            prop_assert_eq!((usize::from(e.above), usize::from(e.below)), (above, below));
        }
    }

    #[test]
    fn one_outlier_among_the_first_three_is_pulled_in() {
        // A half swing first: its value is 16 noise widths off.
        for first in [0, 1, 2] {
            let mut values = [100.0f32, 104.0, 96.0];
            values[first] = 500.0;
            let mut tally = Tally::default();
            for v in values.into_iter().chain([101.0, 99.0, 100.0, 102.0]) {
                tally.add(v, 24.0, 30.0);
            }
            let e = tally.estimate(1.0);
            // Pulled to at most CLAMP scales (the stated noise here) of the median (at most
            // 4 from 100): its share of the mean is at most that over the seven swings.
            assert!(
                (e.value - 100.0).abs() <= (CLAMP * 24.0 + 4.0) / 7.0 + 2.0,
                "first {first}: {e:?}"
            );
        }
    }

    #[test]
    fn a_late_outlier_moves_the_mean_by_at_most_its_clamp() {
        let mut tally = Tally::default();
        for v in [0.0f32, 4.0, -4.0, -2.0, 2.0] {
            tally.add(v, 10.0, 20.0);
        }
        let before = tally.estimate(1.0);
        let reach = super::reach(tally.predictive(), 20.0);
        tally.add(10_000.0, 10.0, 20.0);
        let after = tally.estimate(1.0);
        assert!(
            (after.value - before.value) <= reach / 6.0 + 1.0,
            "{after:?}"
        );
        // It still counts as past the tolerance: the evidence is what the swing showed.
        assert_eq!((after.above, after.n), (1, 6));
    }

    #[test]
    fn the_golfers_spread_is_net_of_the_noise_and_the_uncertainty_never_below_it() {
        let mut tally = Tally::default();
        // Values 3 units apart, each said to be uncertain by 16: all of the scatter is noise.
        for v in [0.0f32, 3.0, -3.0, 1.0] {
            tally.add(v, 16.0, 1000.0);
        }
        let e = tally.estimate(0.5);
        assert_eq!(e.spread, 0.0);
        assert!((e.uncertainty - 16.0 / 2.0 * 0.5).abs() < 1e-6, "{e:?}");
        // A scatter of 20 with noise 8: the golfer's own is √(20² − 8²).
        let mut tally = Tally::default();
        for v in [20.0f32, -20.0, 20.0, -20.0] {
            tally.add(v, 8.0, 1000.0);
        }
        let e = tally.estimate(1.0);
        let spread = (4.0f32 * 400.0 / 3.0).sqrt();
        assert!(
            (e.spread - (spread * spread - 64.0).sqrt()).abs() < 0.5,
            "{e:?}"
        );
    }

    #[test]
    fn an_estimate_clears_a_tolerance_only_by_its_whole_interval() {
        let mut tally = Tally::default();
        for v in [130.0f32, 128.0, 126.0, 131.0, 125.0] {
            tally.add(v, 2.0, 100.0);
        }
        let e = tally.estimate(1.0);
        assert!(e.clears(100.0) && !e.clears(127.0));
        assert!(e.within(140.0) && !e.within(128.0));
        // One value says nothing of the scatter: no interval.
        let mut one = Tally::default();
        one.add(500.0, 1.0, 100.0);
        assert!(
            !one.estimate(1.0).clears(100.0) && one.estimate(1.0).swings_to_settle(100.0).is_none()
        );
    }

    #[test]
    fn the_swings_to_settle_grow_as_the_value_nears_its_tolerance() {
        let tally = |mean: f32| {
            let mut t = Tally::default();
            for d in [-10.0f32, 10.0, -10.0, 10.0] {
                t.add(mean + d, 1.0, 100.0);
            }
            t.estimate(1.0)
        };
        let (far, near) = (tally(130.0), tally(103.0));
        let (far_n, near_n) = (
            far.swings_to_settle(100.0).unwrap(),
            near.swings_to_settle(100.0).unwrap(),
        );
        assert!(far_n < near_n, "{far_n} {near_n}");
        // About (1.65 · 11.5 / 3)² swings for a 3-unit gap with a scatter of 11.5.
        assert!((37..=43).contains(&near_n), "{near_n}");
        // Never fewer than one more swing.
        assert_eq!(far_n, 5);
    }

    #[test]
    fn t_falls_toward_the_normal_quantile() {
        assert!(t95(0).is_infinite());
        assert!((t95(1) - 6.314).abs() < 1e-3 && (t95(30) - 1.697).abs() < 1e-3);
        assert!(t95(31) < t95(30) && t95(1000) > 1.645 && t95(1000) < 1.65);
    }
}
