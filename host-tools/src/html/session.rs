//! A page's range session ([`section`]), before its swings: what they say together as the
//! session tells it ([`Tendencies`]: the tendencies, cause first, or the open question; the
//! swings set aside and why; how consistent the backswing is), then each body-level metric
//! across the swings as small multiples. Element ids: `session`, `tendencies` (or `open`),
//! `set-aside`, `consistency`, `multiples`, and `multiple-NAME` for each metric, NAME as the
//! session's text names it (`backswing`, `thorax_turn_p4`).

use super::{capitalized, escape, Scored, Swing, COACH, COACH_DASH, STUDENT};
use crate::session::{self as told, Reading};
use posecoach_core::score::Phase;
use posecoach_core::session::{body_level_values, Quantity, Tendencies, TOUR_BACKSWING_SPREAD_S};
use posecoach_core::tally::Estimate;
use std::fmt::Write;

/// A small multiple's width: a phone's (390 px less the page's margins), so that its text
/// keeps its size there.
const WIDTH: f32 = 360.0;
/// Its height.
const HEIGHT: f32 = 136.0;
/// The plot's top and bottom.
const TOP: f32 = 26.0;
const BOTTOM: f32 = 112.0;
/// The swings' plot's left and right (the value labels on the left, the session on the right).
const LEFT: f32 = 64.0;
const RIGHT: f32 = WIDTH - 56.0;
/// The session's column's centre.
const SESSION_X: f32 = WIDTH - 28.0;
/// The least font size, px: readable on a phone.
const SMALL: f32 = 11.0;
/// Swing numbers labelled under a chart, at most.
const X_LABELS: usize = 6;

/// A page's range session, as [`section`] draws it.
#[derive(Clone, Debug)]
pub struct SessionSection(String);

impl SessionSection {
    /// The section's HTML.
    pub fn html(&self) -> &str {
        &self.0
    }
}

/// One swing's value of a metric.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dot {
    /// The swing's number in the session, from 1.
    pub swing: usize,
    /// Its value against the coach's, in the metric's own unit (as the session counts it).
    pub value: f32,
    /// Its stated uncertainty (one standard deviation), the same unit.
    pub uncertainty: f32,
    /// Whether the session set the swing aside.
    pub set_aside: bool,
}

/// One body-level metric across a session's swings.
#[derive(Clone, Debug)]
pub struct Metric {
    /// As the session names it: `backswing`, `thorax_turn_p4`.
    pub name: String,
    /// How it reads.
    pub reading: Reading,
    /// The difference from the coach's that advice acts on (infinite where none does).
    pub tolerance: f32,
    /// The session's estimate.
    pub estimate: Estimate,
    /// The swings it was measured in.
    pub dots: Vec<Dot>,
    /// The session's swings on the page: the charts' common axis.
    pub swings: usize,
}

/// The session's part of a page holding `swings`: `None` for one swing alone.
pub fn section(session: &Tendencies<'_>, swings: &[Swing]) -> Option<SessionSection> {
    if swings.len() < 2 {
        return None;
    }
    let heard = heard(session, swings);
    let mut out = String::from("<section id=\"session\"><h2>Range session</h2>\n");
    let scored = swings.iter().filter(|s| s.outcome.is_ok()).count();
    let _ = write!(
        out,
        "<p id=\"session-swings\">{}, {} used",
        swings_of(session.swings()),
        session.used()
    );
    if heard.len() < scored {
        let _ = write!(
            out,
            ": the last {} of this page's scored swings (a new coach or profile starts a \
             session afresh)",
            heard.len()
        );
    }
    out.push_str(".</p>\n");
    tendencies(&mut out, session);
    set_aside(&mut out, session, &heard);
    consistency(&mut out, session);
    multiples(&mut out, &metrics(session, &heard));
    out.push_str("</section>\n");
    Some(SessionSection(out))
}

/// `n` swings, in words.
fn swings_of(n: u16) -> String {
    match n {
        1 => "1 swing".to_string(),
        n => format!("{n} swings"),
    }
}

/// The session's swings among the page's, with their places on the page from 1: every swing
/// scored hears the session, so they are the last `session.swings()` scored.
fn heard<'s>(session: &Tendencies<'_>, swings: &'s [Swing]) -> Vec<(usize, &'s Scored)> {
    let scored: Vec<(usize, &Scored)> = swings
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.outcome.as_ref().ok().map(|scored| (i + 1, scored)))
        .collect();
    let from = scored.len().saturating_sub(usize::from(session.swings()));
    scored[from..].to_vec()
}

/// The tendencies, most important (a cause before what it explains) first, each with its
/// evidence; or that nothing is clear yet, and what would settle the nearest question.
fn tendencies(out: &mut String, session: &Tendencies<'_>) {
    out.push_str("<h3>Tendencies</h3>\n");
    let advice = session.advice();
    if advice.is_empty() {
        let open = told::open_question(session).map_or(String::new(), |q| format!(": {q}"));
        let _ = writeln!(
            out,
            "<p id=\"open\">Nothing is clear yet{}.</p>",
            escape(&open)
        );
        return;
    }
    out.push_str("<ol id=\"tendencies\">\n");
    for t in &advice {
        let _ = writeln!(out, "<li>{}</li>", escape(&t.to_string()));
    }
    out.push_str("</ol>\n");
}

/// The swings set aside, each linked to its section, and why.
fn set_aside(out: &mut String, session: &Tendencies<'_>, heard: &[(usize, &Scored)]) {
    if session.set_aside().is_empty() {
        return;
    }
    out.push_str("<h3>Set aside</h3><ul id=\"set-aside\">\n");
    for s in session.set_aside() {
        let which = match heard.get(usize::from(s.swing).wrapping_sub(1)) {
            Some((page, _)) => format!("<a href=\"#swing-{page}\">Swing {}</a>", s.swing),
            None => format!("Swing {}", s.swing),
        };
        let _ = writeln!(
            out,
            "<li>{which}: {}</li>",
            escape(&told::reason(session, s))
        );
    }
    out.push_str("</ul>\n");
}

/// How consistently the golfer repeats the backswing, net of the measurement noise, beside the
/// tour's.
fn consistency(out: &mut String, session: &Tendencies<'_>) {
    out.push_str("<h3>Consistency</h3><p id=\"consistency\">");
    let q = Quantity::Tempo(Phase::Backswing);
    let counted = session.estimate(q).filter(|e| e.n >= 2);
    let _ = match (counted, Reading::of(session, q)) {
        (Some(e), Some(read)) => {
            let noise = read.spread(e.value, e.noise);
            match e.spread > 0.0 {
                true => write!(
                    out,
                    "Your backswing's duration varies by {} from swing to swing, net of the \
                     measurement noise ({noise} a swing)",
                    read.spread(e.value, e.spread)
                ),
                false => write!(
                    out,
                    "Your backswing's duration varies from swing to swing no more than the \
                     measurement noise ({noise} a swing) hides"
                ),
            }
        }
        _ => write!(
            out,
            "Two swings counted tell how consistently you repeat your backswing"
        ),
    };
    let _ = writeln!(
        out,
        "; tour players repeat theirs within about {TOUR_BACKSWING_SPREAD_S} s. Each chart \
         below gives its metric's spread.</p>"
    );
}

/// Each body-level metric measured in the session's swings, [`Quantity::BODY_LEVEL`] order.
fn metrics(session: &Tendencies<'_>, heard: &[(usize, &Scored)]) -> Vec<Metric> {
    let values: Vec<_> = heard
        .iter()
        .map(|(_, s)| body_level_values(&s.body_level()))
        .collect();
    let set_aside: Vec<usize> = session
        .set_aside()
        .iter()
        .map(|s| usize::from(s.swing))
        .collect();
    Quantity::BODY_LEVEL
        .iter()
        .enumerate()
        .filter_map(|(k, &q)| {
            let dots: Vec<Dot> = values
                .iter()
                .enumerate()
                .filter_map(|(i, swing)| {
                    let (value, uncertainty, _) = swing[k]?;
                    Some(Dot {
                        swing: i + 1,
                        value,
                        uncertainty,
                        set_aside: set_aside.contains(&(i + 1)),
                    })
                })
                .collect();
            if dots.is_empty() {
                return None;
            }
            Some(Metric {
                name: told::name(session, q),
                reading: Reading::of(session, q)?,
                tolerance: q.tolerance(),
                estimate: session.estimate(q)?,
                dots,
                swings: values.len(),
            })
        })
        .collect()
}

/// The small multiples, under a key.
fn multiples(out: &mut String, metrics: &[Metric]) {
    let key = |shape: &str| {
        format!("<svg class=\"key\" width=\"14\" height=\"14\" viewBox=\"0 0 14 14\">{shape}</svg>")
    };
    let _ = writeln!(
        out,
        "<h3>Each metric across the swings</h3><p class=\"note\" id=\"multiples-key\">In the \
         order hit: {} <span style=\"color:{STUDENT}\">a swing</span>, its line &#177; its \
         stated uncertainty; {} a swing set aside; {} <span style=\"color:{STUDENT}\">the \
         session's estimate</span>, its bar the interval a tendency needs wholly outside \
         <span style=\"color:{COACH}\">the coach's value (dashed) and tolerance \
         (shaded)</span>.</p><div class=\"multiples\" id=\"multiples\">",
        key(&format!("<circle cx=\"7\" cy=\"7\" r=\"4\" fill=\"{STUDENT}\"/>")),
        key(&format!(
            "<circle cx=\"7\" cy=\"7\" r=\"4\" fill=\"#fff\" stroke=\"{STUDENT}\" stroke-width=\"1.5\"/>"
        )),
        key(&diamond(7.0, 7.0)),
    );
    for m in metrics {
        chart(out, m);
    }
    out.push_str("</div>\n");
}

/// The session's estimate's mark, centred on (`x`, `y`).
fn diamond(x: f32, y: f32) -> String {
    format!(
        "<path class=\"estimate\" d=\"M{x:.1} {:.1}l5 5l-5 5l-5 -5z\" fill=\"{STUDENT}\"/>",
        y - 5.0
    )
}

impl Metric {
    /// The values drawn, low and high, own unit: the coach's tolerance band, every swing's
    /// value and the session's estimate, with room about them (an interval past it is cut at
    /// the edge).
    fn range(&self) -> (f32, f32) {
        let band = match self.tolerance.is_finite() {
            true => self.tolerance,
            false => 0.0,
        };
        let estimate = (self.estimate.n > 0).then_some(self.estimate.value);
        let (lo, hi) = self
            .dots
            .iter()
            .map(|d| d.value)
            .chain([-band, band])
            .chain(estimate)
            .fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
        // Some room even where every value is the coach's (a tenth of a second of pause).
        let least = if band > 0.0 {
            band
        } else {
            0.1 / self.reading.scale
        };
        let pad = 0.1 * (hi - lo).max(least);
        (lo - pad, hi + pad)
    }

    /// The chart's title: the metric, the session's estimate and its spread.
    fn title(&self) -> String {
        let (e, read) = (&self.estimate, &self.reading);
        let stated = match (e.n, e.uncertainty.is_finite()) {
            (0, _) => "no swing counted".to_string(),
            (_, true) => format!(
                "{} &#177; {}, spread {}",
                escape(&read.text(e.value)),
                escape(&read.amount(e.value, e.uncertainty)),
                escape(&read.spread(e.value, e.spread))
            ),
            (_, false) => escape(&read.text(e.value)),
        };
        format!(
            "<text x=\"4\" y=\"16\" font-size=\"12\"><tspan font-size=\"13\" \
             font-weight=\"bold\">{}</tspan> {stated}</text>",
            escape(&capitalized(&self.name.replace('_', " ")))
        )
    }
}

/// One metric's small multiple: each swing's value (hollow where set aside) with its
/// uncertainty, in the order hit; the coach's value and tolerance band across; the session's
/// estimate with its interval on the right.
pub fn chart(out: &mut String, m: &Metric) {
    let (lo, hi) = m.range();
    let y = |v: f32| (BOTTOM - (v - lo) / (hi - lo) * (BOTTOM - TOP)).clamp(TOP, BOTTOM);
    let _ = write!(
        out,
        "<svg class=\"multiple\" id=\"multiple-{}\" width=\"{WIDTH}\" height=\"{HEIGHT}\" \
         viewBox=\"0 0 {WIDTH} {HEIGHT}\">{}",
        escape(&m.name),
        m.title()
    );
    coach(out, m, &y);
    values(out, m, (lo, hi), &y);
    swings(out, m, &y);
    session(out, &m.estimate, &y);
    out.push_str("</svg>\n");
}

/// The coach's value (dashed) and tolerance band (shaded) across the chart.
fn coach(out: &mut String, m: &Metric, y: &impl Fn(f32) -> f32) {
    let right = WIDTH - 4.0;
    if m.tolerance.is_finite() {
        let (top, bottom) = (y(m.tolerance), y(-m.tolerance));
        let _ = write!(
            out,
            "<rect class=\"band\" x=\"{LEFT}\" y=\"{top:.1}\" width=\"{:.1}\" height=\"{:.1}\" \
             fill=\"{COACH}\" fill-opacity=\"0.13\"/>",
            right - LEFT,
            bottom - top
        );
    }
    let _ = write!(
        out,
        "<line class=\"coach\" x1=\"{LEFT}\" y1=\"{c:.1}\" x2=\"{right}\" y2=\"{c:.1}\" \
         stroke=\"{COACH}\" stroke-width=\"1.5\" stroke-dasharray=\"{COACH_DASH}\"/>",
        c = y(0.0)
    );
}

/// The value labels on the left: the coach's, and the ends of the range where they do not
/// crowd it.
fn values(out: &mut String, m: &Metric, (lo, hi): (f32, f32), y: &impl Fn(f32) -> f32) {
    let label = |out: &mut String, v: f32, colour: &str| {
        let _ = write!(
            out,
            "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"{SMALL}\" text-anchor=\"end\" \
             fill=\"{colour}\">{}</text>",
            LEFT - 5.0,
            y(v) + 4.0,
            escape(&m.reading.text(v))
        );
    };
    label(out, 0.0, COACH);
    for end in [lo, hi] {
        if (y(end) - y(0.0)).abs() >= SMALL + 3.0 {
            label(out, end, "#555");
        }
    }
}

/// Each swing's dot and uncertainty, and the swings' numbers under them.
fn swings(out: &mut String, m: &Metric, y: &impl Fn(f32) -> f32) {
    let step = (RIGHT - LEFT) / m.swings.max(1) as f32;
    let x = |swing: usize| LEFT + (swing as f32 - 0.5) * step;
    let r = (step * 0.3).clamp(1.5, 4.0);
    for d in &m.dots {
        let (cx, cy) = (x(d.swing), y(d.value));
        if d.uncertainty > 0.0 {
            let _ = write!(
                out,
                "<line class=\"interval\" x1=\"{cx:.1}\" y1=\"{:.1}\" x2=\"{cx:.1}\" y2=\"{:.1}\" \
                 stroke=\"{STUDENT}\" stroke-width=\"1.5\"/>",
                y(d.value + d.uncertainty),
                y(d.value - d.uncertainty)
            );
        }
        let (class, fill) = match d.set_aside {
            true => ("swing set-aside", "#fff"),
            false => ("swing", STUDENT),
        };
        let _ = write!(
            out,
            "<circle class=\"{class}\" cx=\"{cx:.1}\" cy=\"{cy:.1}\" r=\"{r:.1}\" fill=\"{fill}\" \
             stroke=\"{STUDENT}\" stroke-width=\"1.5\"><title>swing {}: {} &#177; {}{}</title></circle>",
            d.swing,
            escape(&m.reading.text(d.value)),
            escape(&m.reading.amount(d.value, d.uncertainty)),
            if d.set_aside { ", set aside" } else { "" }
        );
    }
    let every = m.swings.div_ceil(X_LABELS).max(1);
    for swing in (1..=m.swings).step_by(every) {
        let _ = write!(
            out,
            "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"{SMALL}\" text-anchor=\"middle\">{swing}</text>",
            x(swing),
            BOTTOM + 15.0
        );
    }
}

/// The session's estimate and its interval (each end a one-sided 95 % bound, as advice takes
/// it) in the column on the right.
fn session(out: &mut String, e: &Estimate, y: &impl Fn(f32) -> f32) {
    let _ = write!(
        out,
        "<text x=\"{SESSION_X}\" y=\"{:.1}\" font-size=\"{SMALL}\" text-anchor=\"middle\">session</text>",
        BOTTOM + 15.0
    );
    if e.n == 0 {
        return;
    }
    let margin = e.margin();
    if margin.is_finite() {
        let _ = write!(
            out,
            "<line class=\"session\" x1=\"{SESSION_X}\" y1=\"{:.1}\" x2=\"{SESSION_X}\" \
             y2=\"{:.1}\" stroke=\"{STUDENT}\" stroke-width=\"7\" stroke-opacity=\"0.4\"/>",
            y(e.value + margin),
            y(e.value - margin)
        );
    }
    out.push_str(&diamond(SESSION_X, y(e.value)));
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_core::session::JointTallies;

    /// A chart of the backswing over `swings`, with these dots and a session estimate of
    /// `estimate` (ln of the ratio) from `n` swings.
    fn backswing(dots: &[Dot], swings: usize, (estimate, n): (f32, u8)) -> String {
        let mut joints = [JointTallies::EMPTY; 0];
        let session = Tendencies::new(&mut joints);
        let q = Quantity::Tempo(Phase::Backswing);
        let metric = Metric {
            name: told::name(&session, q),
            reading: Reading::of(&session, q).unwrap(),
            tolerance: q.tolerance(),
            estimate: Estimate {
                n,
                value: estimate,
                uncertainty: 0.02,
                spread: 0.01,
                noise: 0.02,
                above: n,
                below: 0,
            },
            dots: dots.to_vec(),
            swings,
        };
        let mut out = String::new();
        chart(&mut out, &metric);
        out
    }

    fn dot(swing: usize, value: f32, set_aside: bool) -> Dot {
        Dot {
            swing,
            value,
            uncertainty: 0.03,
            set_aside,
        }
    }

    #[test]
    fn a_chart_draws_a_dot_for_each_swing_measured_and_hollows_those_set_aside() {
        // Six swings, the fourth not measured, the fifth set aside.
        let dots: Vec<Dot> = [1, 2, 3, 5, 6]
            .iter()
            .map(|&s| dot(s, 0.25 + 0.01 * s as f32, s == 5))
            .collect();
        let svg = backswing(&dots, 6, (0.26, 4));
        assert_eq!(svg.matches("class=\"swing").count(), 5);
        assert_eq!(svg.matches("class=\"swing set-aside\"").count(), 1);
        assert_eq!(svg.matches("class=\"interval\"").count(), 5);
        assert!(svg.contains("id=\"multiple-backswing\""));
        // The coach's value and band, and the session's estimate with its interval.
        for part in [
            "class=\"coach\"",
            "class=\"band\"",
            "class=\"session\"",
            "class=\"estimate\"",
        ] {
            assert_eq!(svg.matches(part).count(), 1, "{part}");
        }
        assert!(svg.contains("×1.30 &#177; 0.03"), "{svg}");
    }

    #[test]
    fn only_a_page_of_several_swings_has_a_session() {
        let mut joints = [JointTallies::EMPTY; 0];
        let session = Tendencies::new(&mut joints);
        let unscored = Swing {
            heading: "swing 1".into(),
            outcome: Err("no impact found".into()),
        };
        assert!(section(&session, std::slice::from_ref(&unscored)).is_none());
        let two = section(&session, &[unscored.clone(), unscored]).unwrap();
        let html = two.html();
        for part in [
            "id=\"session\"",
            "id=\"open\"",
            "id=\"consistency\"",
            "id=\"multiples\"",
        ] {
            assert!(html.contains(part), "{part}");
        }
        // No swing heard: nothing to chart.
        assert!(!html.contains("class=\"multiple\""));
    }

    #[test]
    fn a_chart_stays_inside_its_box_and_its_text_readable() {
        // A set-aside swing far off, and intervals past the range: nothing past the plot.
        let dots = [dot(1, 0.1, false), dot(2, -2.0, true), dot(3, 0.12, false)];
        let svg = backswing(&dots, 3, (0.11, 1));
        let numbers = |attribute: &str| -> Vec<f32> {
            svg.split(&format!(" {attribute}=\""))
                .skip(1)
                .map(|s| s[..s.find('"').unwrap()].parse().unwrap())
                .collect()
        };
        for x in numbers("cx").into_iter().chain(numbers("x1")) {
            assert!((0.0..=WIDTH).contains(&x), "{x}");
        }
        for y in numbers("cy")
            .into_iter()
            .chain(numbers("y1"))
            .chain(numbers("y2"))
        {
            assert!((TOP..=BOTTOM).contains(&y), "{y}");
        }
        assert!(numbers("font-size").iter().all(|&s| s >= SMALL));
        // One swing counted: its estimate, no interval yet.
        assert!(!svg.contains("class=\"session\"") && svg.contains("class=\"estimate\""));
    }
}
