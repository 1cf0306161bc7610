//! The HTML swing report: one self-contained page (inline SVG, no scripts, no network).
//!
//! Per swing, in the order a coach reads it: the score and the advice; the student (blue,
//! solid) over the virtual coach (vermillion, dashed) at each key event, face-on and down the line, each swing in its
//! own stance frame (as the spatial advice measures it); the tempo of each phase; the DTW path
//! over the frame-cost matrix with the events; and the deviation of the most-advised joints
//! along the alignment; the body metrics at P1 to P10 and the kinematic sequence with its
//! graph. Element ids (`score-N`, `advice-N`, `poses-N`, `body-N`, `sequence-N`,
//! `sequence-chart-N`, `tempo-N`, `dtw-N`, `deviation-N` for swing `N` from 1) let tests and
//! scripts find each part.
//!
//! A page of several swings opens with their range session ([`session`]).

pub mod session;

use crate::table::{input_error, peak_text, whole, with_spread, BodyRow, KEY_METRICS, PLUS_MINUS};
use base64::Engine;
use posecoach_adapters::session::Compared;
use posecoach_core::body::{self, Link, Stance};
use posecoach_core::events::{Event, Position, SwingEvents};
use posecoach_core::frames::Frames;
use posecoach_core::joint::Joint;
use posecoach_core::score::{Advice, BodyLevel, Report, SPATIAL_THRESHOLD_M};
use posecoach_core::sequence::{self, KinematicSequence, GAP_TOLERANCE_S};
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;
use std::fmt::Write;

/// The student's colour: blue, and solid lines.
const STUDENT: &str = "#0072b2";
/// The virtual coach's colour: vermillion, and dashed lines. The two (Okabe and Ito's palette)
/// stay apart for the common colour-vision deficiencies, where green and red do not.
const COACH: &str = "#d55e00";
/// The virtual coach's dash pattern, the second cue beside its colour.
const COACH_DASH: &str = "5 3";
/// Most cells per side of the drawn cost matrix (larger matrices are sampled).
const MATRIX_CELLS: usize = 300;
/// Joints drawn in the deviation chart.
const DEVIATION_JOINTS: usize = 4;
/// Colours of the deviation chart's joints.
const PALETTE: [&str; DEVIATION_JOINTS] = ["#7b3294", "#e66101", "#0571b0", "#4d4d4d"];

/// Points of a pose on the screen.
type Points = Vec<(f32, f32)>;

/// A swing's kinematic sequence with the time of its top (frames) and its rate, if it has one.
pub type Sequenced = Option<(KinematicSequence, f32, f32)>;

/// A scored swing and the motions it compares, owned.
#[derive(Clone, Debug)]
pub struct Scored {
    /// The report.
    pub report: Report,
    /// The student's skeleton.
    pub skeleton: Skeleton,
    /// The student's swing, frame-major.
    pub student: Vec<Vec3>,
    /// Its rate, Hz.
    pub student_hz: f32,
    /// The virtual coach's swing on the student's skeleton, frame-major.
    pub coach: Vec<Vec3>,
    /// Its rate, Hz.
    pub coach_hz: f32,
}

impl Scored {
    /// A copy of `report` and the swings it compares.
    pub fn new(report: &Report, compared: &Compared<'_>) -> Scored {
        Scored {
            report: report.clone(),
            skeleton: compared.skeleton.clone(),
            student: compared.student.iter().collect(),
            student_hz: compared.student_hz,
            coach: compared.coach.iter().collect(),
            coach_hz: compared.coach_hz,
        }
    }

    /// `swing` (the student's or the coach's), as the core's readers take it.
    fn as_frames<'s>(&self, swing: &'s [Vec3]) -> Frames<'s> {
        Frames::metres(swing, self.skeleton.len())
    }

    /// Both swings' body metrics at each P-position either has, the student's with their
    /// uncertainties.
    pub fn body_table(&self) -> Vec<BodyRow> {
        let r = &self.report;
        let table = |swing: &[Vec3], events: &SwingEvents| {
            body::at_positions(&self.skeleton, self.as_frames(swing), events)
                .unwrap_or([None; Position::ALL.len()])
        };
        let (student, coach) = (
            table(&self.student, &r.student_events),
            table(&self.coach, &r.coach_events),
        );
        let spread = body::spread_at_positions(
            &self.skeleton,
            self.as_frames(&self.student),
            &r.student_events,
            &input_error(r, self.student_hz),
        )
        .unwrap_or([None; Position::ALL.len()]);
        Position::ALL
            .into_iter()
            .filter(|&p| student[p as usize].is_some() || coach[p as usize].is_some())
            .map(|p| BodyRow {
                position: p,
                student: student[p as usize],
                spread: spread[p as usize],
                coach: coach[p as usize],
            })
            .collect()
    }

    /// Both swings' kinematic sequences (`None` for a putt), each with its time of the top in
    /// frames and its rate.
    pub fn sequences(&self) -> [Sequenced; 2] {
        let of = |swing: &[Vec3], hz: f32, events: &SwingEvents| {
            let top = events.time(Position::P4)?;
            let sequence =
                sequence::kinematic_sequence(&self.skeleton, self.as_frames(swing), hz, events)
                    .ok()??;
            Some((sequence, top, hz))
        };
        [
            of(&self.student, self.student_hz, &self.report.student_events),
            of(&self.coach, self.coach_hz, &self.report.coach_events),
        ]
    }

    /// Its body-level results, as a session hears them.
    pub fn body_level(&self) -> BodyLevel<'_> {
        let r = &self.report;
        BodyLevel {
            lead: r.student_events.lead,
            tempo: &r.tempo,
            pause_s: (
                r.student_events.pause() / self.student_hz,
                r.coach_events.pause() / self.coach_hz,
            ),
            body: &r.body,
            coach_rate: &[],
            gaps: &r.gaps,
        }
    }

    fn frame<'a>(&self, swing: &'a [Vec3], f: usize) -> &'a [Vec3] {
        let n = self.skeleton.len();
        &swing[f * n..(f + 1) * n]
    }

    fn frames(&self, swing: &[Vec3]) -> usize {
        swing.len() / self.skeleton.len().max(1)
    }

    /// The coach frame the alignment first matches with student frame `i`.
    fn matched(&self, i: usize) -> usize {
        let path = &self.report.path;
        path.iter()
            .find(|&&(a, _)| a as usize >= i)
            .or(path.last())
            .map_or(0, |&(_, b)| b as usize)
    }

    fn stances(&self) -> (Stance, Stance) {
        let (s, c) = (&self.report.student_events, &self.report.coach_events);
        (
            Stance::new(
                &self.skeleton,
                self.frame(&self.student, s.address()),
                s.lead,
            ),
            Stance::new(&self.skeleton, self.frame(&self.coach, c.address()), c.lead),
        )
    }
}

/// One swing of a page: its heading, and its report or why it has none.
#[derive(Clone, Debug)]
pub struct Swing {
    /// Shown above the swing ("swing 2 at 14.20 s").
    pub heading: String,
    /// The scored swing, or why it was not scored.
    pub outcome: Result<Scored, String>,
}

/// The whole page: `title`, a line per `notes` entry (inputs, retargeter), the range session
/// where `session` holds one ([`session::section`]), then each swing.
pub fn page(
    title: &str,
    notes: &[String],
    session: Option<&session::SessionSection>,
    swings: &[Swing],
) -> String {
    let mut out = String::new();
    let _ = write!(
        out,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{}</title><style>{STYLE}</style></head><body>\n<h1>{}</h1>\n",
        escape(title),
        escape(title)
    );
    for note in notes {
        let _ = writeln!(out, "<p class=\"note\">{}</p>", escape(note));
    }
    let _ = writeln!(
        out,
        "<p class=\"legend\"><svg class=\"key\" width=\"28\" height=\"10\"><line x1=\"2\" y1=\"5\" x2=\"26\" y2=\"5\" \
         stroke=\"{STUDENT}\" stroke-width=\"2.5\"/></svg> <span style=\"color:{STUDENT}\">you</span> \
         <svg class=\"key\" width=\"28\" height=\"10\"><line x1=\"2\" y1=\"5\" x2=\"26\" y2=\"5\" stroke=\"{COACH}\" \
         stroke-width=\"2.5\" stroke-dasharray=\"{COACH_DASH}\"/></svg> <span style=\"color:{COACH}\">virtual \
         coach (the coach's swing on your body)</span></p>"
    );
    if let Some(session) = session {
        out.push_str(session.html());
    }
    if swings.is_empty() {
        out.push_str("<p id=\"no-swing\">No swing found.</p>\n");
    }
    for (i, swing) in swings.iter().enumerate() {
        let n = i + 1;
        let _ = writeln!(
            out,
            "<section id=\"swing-{n}\"><h2>{}</h2>",
            escape(&swing.heading)
        );
        match &swing.outcome {
            Ok(scored) => section(&mut out, n, scored),
            Err(why) => {
                let _ = writeln!(out, "<p class=\"error\">Not scored: {}</p>", escape(why));
            }
        }
        out.push_str("</section>\n");
    }
    out.push_str("</body></html>\n");
    out
}

const STYLE: &str = "body{font-family:sans-serif;margin:24px;color:#222;max-width:1240px}\
@media(max-width:600px){body{margin:8px}}svg{max-width:100%;height:auto}\
h1,h2,p,li{overflow-wrap:anywhere}\
h2{border-bottom:1px solid #ccc}.note{color:#555;margin:2px 0}.score{font-size:44px;font-weight:bold}\
.poses{display:flex;flex-wrap:wrap;gap:6px}.pose{text-align:center;font-size:12px;width:146px}\
svg{background:#fafafa;border:1px solid #ddd}.error{color:#b00}li{margin:4px 0}\
text{font-family:sans-serif}.wide{overflow-x:auto}table{border-collapse:collapse;font-size:13px}\
td,th{border-bottom:1px solid #ddd;padding:3px 6px;text-align:right;white-space:nowrap}\
svg.key{border:none;background:none}tbody th{white-space:normal;text-align:left;min-width:9em}\
.swamped{color:#999}.multiples{display:flex;flex-wrap:wrap;gap:8px}";

/// What a report says of a swing whose input held the root still
/// ([`posecoach_core::score::Report::root_held`]).
pub const ROOT_HELD: &str = "The input holds your hips still (landmarks centred on the hips, or a \
     root the sensors fix): the coach is compared about its hips too, and the hips' sway and \
     thrust are not judged.";

fn section(out: &mut String, n: usize, s: &Scored) {
    let r = &s.report;
    let _ = writeln!(
        out,
        "<p id=\"score-{n}\"><span class=\"score\">{:.0}</span> / 100 &#8212; mean joint distance \
         {:.1} cm along the alignment; tempo (backswing:downswing) you {:.1}:1, coach {:.1}:1</p>",
        r.score,
        r.normalized * 100.0,
        r.student_tempo_ratio,
        r.coach_tempo_ratio
    );
    if r.root_held {
        let _ = writeln!(
            out,
            "<p class=\"note\" id=\"root-held-{n}\">{}</p>",
            escape(ROOT_HELD)
        );
    }
    let _ = writeln!(out, "<h3>Advice</h3><ol id=\"advice-{n}\">");
    for advice in &r.advice {
        let _ = writeln!(out, "<li>{}</li>", escape(&advice.to_string()));
    }
    if r.advice.is_empty() {
        out.push_str("<li>Nothing to fix: tempo and positions are within tolerance.</li>\n");
    }
    out.push_str("</ol>\n");
    poses(out, n, s);
    body_table(out, n, s);
    tempo(out, n, r);
    dtw(out, n, s);
    deviation(out, n, s);
}

/// The body metrics at each P-position, yours with the coach's, and both kinematic sequences.
fn body_table(out: &mut String, n: usize, s: &Scored) {
    let _ = write!(
        out,
        "<h3>Body at each position</h3><p class=\"note\">Degrees; shifts since address in cm; \
         <span style=\"color:{COACH}\">the coach's in brackets</span>.</p>\
         <div class=\"wide\"><table id=\"body-{n}\"><thead><tr><th>position</th>"
    );
    for (name, unit, _, _) in &KEY_METRICS {
        let _ = write!(out, "<th>{} ({unit})</th>", name.replace('_', " "));
    }
    out.push_str("</tr></thead><tbody>\n");
    for row in s.body_table() {
        let _ = write!(
            out,
            "<tr><th>{} <small>{}</small></th>",
            row.position.name(),
            escape(row.position.moment())
        );
        for metric in &KEY_METRICS {
            let (you, swamped) = with_spread(&row, metric);
            let _ = write!(
                out,
                "<td{}>{you} <span style=\"color:{COACH}\">({})</span></td>",
                if swamped { " class=\"swamped\"" } else { "" },
                whole(row.coach, metric.3)
            );
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody></table></div>\n");
    let _ = write!(out, "<p class=\"note\">{}</p>", escape(PLUS_MINUS));
    let sequences = s.sequences();
    let _ = write!(out, "<h3>Kinematic sequence</h3><ul id=\"sequence-{n}\">");
    for (who, sequence) in ["You", "Coach"].into_iter().zip(sequences) {
        let Some((k, top, hz)) = sequence else {
            continue;
        };
        let peaks: Vec<String> = Link::ALL
            .iter()
            .filter_map(|&l| {
                k.peak(l).map(|p| {
                    let (text, swamped) = peak_text(&p, top, hz, who == "Coach");
                    let name = l.name().replace('_', " ");
                    match swamped {
                        true => format!("<span class=\"swamped\">{name} {text}</span>"),
                        false => format!("{name} {text}"),
                    }
                })
            })
            .collect();
        let order: Vec<String> = k
            .order()
            .iter()
            .map(|l| l.name().replace('_', " "))
            .collect();
        let _ = write!(
            out,
            "<li>{who}: {} (&#176;/s at ms after the top); peaking {}</li>",
            peaks.join(", "),
            order.join(", ")
        );
    }
    for g in &s.report.gaps {
        let ms = |v: f32| v * 1000.0 + 0.0;
        let _ = write!(
            out,
            "<li class=\"gap\">{} to {}: you {:.0} &#177; {:.0} ms, coach {:.0} ms (tolerance {:.0}){}</li>",
            g.first.name().replace('_', " "),
            g.then.name().replace('_', " "),
            ms(g.student_s),
            ms(g.uncertainty_s),
            ms(g.coach_s),
            ms(GAP_TOLERANCE_S),
            if Advice::is_clear(g) { ": past it" } else { "" }
        );
    }
    out.push_str("</ul>\n");
    sequence_chart(out, n, s, sequences);
}

/// The kinematic sequence's graph: each link's rotational speed from just before the top to
/// impact, yours solid and the coach's dashed, each link in its colour, the peaks the sequence
/// found marked (`sequences`, as [`Scored::sequences`] gives them); time from each swing's
/// own top.
fn sequence_chart(out: &mut String, n: usize, s: &Scored, sequences: [Sequenced; 2]) {
    const WIDTH: f32 = 560.0;
    const HEIGHT: f32 = 240.0;
    const LEFT: f32 = 52.0;
    const BOTTOM: f32 = 34.0;
    /// Drawn from this long before the top, seconds.
    const BEFORE_S: f32 = 0.05;
    // Per swing: its curves in Link order as (ms from its top, deg/s), its peaks, its dashes.
    let mut drawn = Vec::new();
    let swings = [
        (&s.student, &s.report.student_events, None),
        (&s.coach, &s.report.coach_events, Some(COACH_DASH)),
    ];
    for ((swing, events, dash), sequence) in swings.into_iter().zip(sequences) {
        let (Some((sequence, top, hz)), Some(last), Ok(body)) = (
            sequence,
            events.frame(Position::P7),
            body::Body::new(&s.skeleton, events.lead),
        ) else {
            continue;
        };
        let first = (top - BEFORE_S * hz).max(0.0) as usize;
        let ms = |t: f32| (t - top) / hz * 1000.0;
        let curves: Vec<Vec<(f32, f32)>> = Link::ALL
            .iter()
            .map(|&link| {
                (first..=last)
                    .filter_map(|t| {
                        let v = body.speed(link, s.as_frames(swing), hz, t)?;
                        Some((ms(t as f32), v))
                    })
                    .collect()
            })
            .collect();
        let peaks = Link::ALL.map(|l| sequence.peak(l).map(|p| (ms(p.time), p.speed)));
        drawn.push((curves, peaks, dash));
    }
    let points = drawn.iter().flat_map(|(c, _, _)| c.iter().flatten());
    let (mut t0, mut t1, mut fastest) = (0.0f32, 1.0f32, 100.0f32);
    for &(t, v) in points {
        (t0, t1, fastest) = (t0.min(t), t1.max(t), fastest.max(v));
    }
    let step = if fastest > 1500.0 { 500.0 } else { 250.0 };
    let fastest = (fastest / step).ceil() * step;
    let x_of = |t: f32| LEFT + (t - t0) / (t1 - t0) * (WIDTH - LEFT - 12.0);
    let y_of = |v: f32| HEIGHT - BOTTOM - v / fastest * (HEIGHT - BOTTOM - 24.0);
    let _ = write!(
        out,
        "<svg id=\"sequence-chart-{n}\" width=\"{WIDTH}\" height=\"{HEIGHT}\" \
         viewBox=\"0 0 {WIDTH} {HEIGHT}\">"
    );
    let mut v = 0.0;
    while v <= fastest {
        let _ = write!(
            out,
            "<line x1=\"{LEFT}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"#ddd\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" font-size=\"10\" text-anchor=\"end\">{v:.0}</text>",
            WIDTH - 12.0,
            LEFT - 4.0,
            y_of(v) + 3.0,
            y = y_of(v)
        );
        v += step;
    }
    let mut t = (t0 / 100.0).ceil() * 100.0 + 0.0;
    while t <= t1 {
        let x = x_of(t);
        let _ = write!(
            out,
            "<line x1=\"{x:.1}\" y1=\"{:.1}\" x2=\"{x:.1}\" y2=\"{:.1}\" stroke=\"#999\"/>\
             <text x=\"{x:.1}\" y=\"{:.1}\" font-size=\"10\" text-anchor=\"middle\">{t:.0}</text>",
            HEIGHT - BOTTOM,
            HEIGHT - BOTTOM + 4.0,
            HEIGHT - BOTTOM + 15.0
        );
        t += 100.0;
    }
    let _ = write!(
        out,
        "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"11\" text-anchor=\"middle\">ms after the top \
         (each swing its own)</text><text x=\"12\" y=\"{:.1}\" font-size=\"11\" \
         transform=\"rotate(-90 12 {:.1})\" text-anchor=\"middle\">degrees per second</text>",
        (LEFT + WIDTH) / 2.0,
        HEIGHT - 4.0,
        (HEIGHT - BOTTOM) / 2.0,
        (HEIGHT - BOTTOM) / 2.0
    );
    for (curves, peaks, dash) in &drawn {
        let dashed = dash.map_or(String::new(), |d| format!(" stroke-dasharray=\"{d}\""));
        for (k, curve) in curves.iter().enumerate() {
            let colour = PALETTE[k];
            let line: Vec<String> = curve
                .iter()
                .map(|&(t, v)| format!("{:.1},{:.1}", x_of(t), y_of(v)))
                .collect();
            if line.is_empty() {
                continue;
            }
            let _ = write!(
                out,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.6\"{dashed}/>",
                line.join(" ")
            );
            if let Some((t, v)) = peaks[k] {
                let fill = if dash.is_some() { "white" } else { colour };
                let _ = write!(
                    out,
                    "<circle class=\"peak\" cx=\"{:.1}\" cy=\"{:.1}\" r=\"3.5\" fill=\"{fill}\" \
                     stroke=\"{colour}\"/>",
                    x_of(t),
                    y_of(v)
                );
            }
        }
    }
    for (k, link) in Link::ALL.iter().enumerate() {
        let _ = write!(
            out,
            "<text x=\"{:.1}\" y=\"14\" font-size=\"11\" fill=\"{}\">{}</text>",
            LEFT + 8.0 + k as f32 * 90.0,
            PALETTE[k],
            link.name().replace('_', " ")
        );
    }
    out.push_str("</svg>\n");
}

/// A view of the stance frame: screen x and y (down) from (toward target, toward ball, up).
#[derive(Clone, Copy)]
enum View {
    /// From in front of the golfer: the target to the viewer's left for a right-hander.
    FaceOn,
    /// From behind the golfer, along the target line: the ball to the right.
    DownTheLine,
}

impl View {
    fn project(self, p: Vec3) -> (f32, f32) {
        match self {
            View::FaceOn => (-p.x, -p.z),
            View::DownTheLine => (p.y, -p.z),
        }
    }

    fn name(self) -> &'static str {
        match self {
            View::FaceOn => "face-on",
            View::DownTheLine => "down the line",
        }
    }
}

fn poses(out: &mut String, n: usize, s: &Scored) {
    const SIZE: f32 = 140.0;
    let (student_stance, coach_stance) = s.stances();
    let events: Vec<(Event, usize, usize)> = s
        .report
        .student_events
        .iter()
        .map(|(e, i)| (e, i, s.matched(i)))
        .collect();
    let _ = writeln!(out, "<h3>Key positions</h3><div id=\"poses-{n}\">");
    for view in [View::FaceOn, View::DownTheLine] {
        let pose = |swing: &[Vec3], stance: &Stance, f: usize| -> Points {
            s.frame(swing, f)
                .iter()
                .map(|&p| view.project(stance.local(p)))
                .collect()
        };
        let drawn: Vec<[Points; 2]> = events
            .iter()
            .map(|&(_, i, j)| {
                [
                    pose(&s.student, &student_stance, i),
                    pose(&s.coach, &coach_stance, j),
                ]
            })
            .collect();
        let all = drawn.iter().flatten().flatten();
        let (x0, x1, y0, y1) = all.fold(
            (f32::MAX, f32::MIN, f32::MAX, f32::MIN),
            |(x0, x1, y0, y1), &(x, y)| (x0.min(x), x1.max(x), y0.min(y), y1.max(y)),
        );
        let span = (x1 - x0).max(y1 - y0).max(1e-3) * 1.08;
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let to_px = |(x, y): (f32, f32)| {
            (
                SIZE / 2.0 + (x - cx) / span * SIZE,
                SIZE / 2.0 + (y - cy) / span * SIZE,
            )
        };
        let _ = writeln!(
            out,
            "<p>{} view{}</p><div class=\"poses\">",
            capitalized(view.name()),
            match view {
                View::FaceOn => " (target to the left for a right-handed golfer)",
                View::DownTheLine => " (looking at the target, the ball to the right)",
            }
        );
        for (&(event, i, j), [student, coach]) in events.iter().zip(&drawn) {
            let _ = write!(
                out,
                "<div class=\"pose\"><svg class=\"pose-svg\" width=\"{SIZE}\" height=\"{SIZE}\" \
                 viewBox=\"0 0 {SIZE} {SIZE}\">"
            );
            // The ground, which way the target (face on) or the ball (down the line) lies, and
            // the ball where the club head rested at address.
            let ground = to_px((0.0, 0.0)).1;
            let (arrow, label) = match view {
                View::FaceOn => ("&#8592;", "target"),
                View::DownTheLine => ("&#8594;", "ball"),
            };
            let _ = write!(
                out,
                "<line class=\"ground\" x1=\"0\" y1=\"{ground:.1}\" x2=\"{SIZE}\" y2=\"{ground:.1}\" \
                 stroke=\"#8c6d31\" stroke-width=\"1.5\"/><text x=\"4\" y=\"{:.1}\" font-size=\"9\" \
                 fill=\"#555\">{arrow} {label}</text>",
                (ground + 11.0).min(SIZE - 2.0)
            );
            if let Some(head) = s.skeleton.index_of(Joint::ClubHead) {
                let at = s.report.student_events.address();
                let p = student_stance.local(s.frame(&s.student, at)[head]);
                let (x, y) = to_px(view.project(Vec3::new(p.x, p.y, 0.0)));
                let _ = write!(
                    out,
                    "<circle class=\"ball\" cx=\"{x:.1}\" cy=\"{:.1}\" r=\"2.5\" fill=\"white\" \
                     stroke=\"#333\"/>",
                    y - 2.5
                );
            }
            for (points, colour, width, dash) in [
                (coach, COACH, 2.6, Some(COACH_DASH)),
                (student, STUDENT, 1.8, None),
            ] {
                skeleton_lines(out, &s.skeleton, points, &to_px, colour, width, dash);
            }
            // The joints the advice names at this event, ringed on the student.
            for d in s.report.spatial.iter().filter(|d| d.event == event) {
                if let Some(k) = s.skeleton.index_of(d.joint) {
                    let (x, y) = to_px(student[k]);
                    let _ = write!(
                        out,
                        "<circle class=\"advised\" cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"5\" fill=\"none\" \
                         stroke=\"#000\" stroke-width=\"1.2\"/>"
                    );
                }
            }
            let _ = writeln!(
                out,
                "</svg><br><b>{}</b><br><span class=\"frames\">you {:.2} s, coach {:.2} s</span></div>",
                event_label(event),
                i as f32 / s.student_hz,
                j as f32 / s.coach_hz
            );
        }
        out.push_str("</div>\n");
    }
    out.push_str("</div>\n");
}

fn skeleton_lines(
    out: &mut String,
    skeleton: &Skeleton,
    points: &[(f32, f32)],
    to_px: &impl Fn((f32, f32)) -> (f32, f32),
    colour: &str,
    width: f32,
    dash: Option<&str>,
) {
    let dashed = dash.map_or(String::new(), |d| format!(" stroke-dasharray=\"{d}\""));
    let _ = write!(
        out,
        "<g stroke=\"{colour}\" stroke-width=\"{width}\" stroke-linecap=\"round\"{dashed}>"
    );
    for k in 1..skeleton.len() {
        let Some(parent) = skeleton.parent(k) else {
            continue;
        };
        let club = skeleton.joint(k).is_some_and(Joint::is_club);
        let ((x1, y1), (x2, y2)) = (to_px(points[parent]), to_px(points[k]));
        let dash = if club {
            " stroke-dasharray=\"3 2\""
        } else {
            ""
        };
        let _ = write!(
            out,
            "<line x1=\"{x1:.1}\" y1=\"{y1:.1}\" x2=\"{x2:.1}\" y2=\"{y2:.1}\"{dash}/>"
        );
    }
    out.push_str("</g>");
}

/// The tempo chart: per phase its verdict, then both durations as bars. Narrow enough for a
/// phone's width at its own scale, so its text keeps its size there.
fn tempo(out: &mut String, n: usize, r: &Report) {
    const WIDTH: f32 = 360.0;
    const ROW: f32 = 54.0;
    const LABEL: f32 = 84.0;
    let longest = r
        .tempo
        .iter()
        .map(|t| t.student_s.max(t.coach_s))
        .fold(1e-3, f32::max);
    let height = ROW * r.tempo.len() as f32 + 40.0;
    let scale = (WIDTH - LABEL - 8.0) / longest;
    let _ = writeln!(
        out,
        "<h3>Tempo</h3><svg id=\"tempo-{n}\" width=\"{WIDTH}\" height=\"{height}\" \
         viewBox=\"0 0 {WIDTH} {height}\">"
    );
    for (row, t) in r.tempo.iter().enumerate() {
        let y = 4.0 + row as f32 * ROW;
        let _ = write!(
            out,
            "<text x=\"4\" y=\"{:.1}\" font-size=\"13\"><tspan font-weight=\"bold\">{}</tspan> \
             {} (&#215;{:.2} &#177; {:.2})</text>",
            y + 13.0,
            capitalized(&t.phase.name().replace('_', " ")),
            t.verdict.name(),
            t.ratio,
            t.ratio_uncertainty
        );
        for (k, (seconds, colour, who)) in
            [(t.student_s, STUDENT, "you"), (t.coach_s, COACH, "coach")]
                .into_iter()
                .enumerate()
        {
            let top = y + 19.0 + k as f32 * 16.0;
            let _ = write!(
                out,
                "<text x=\"4\" y=\"{:.1}\" font-size=\"12\">{who} {seconds:.2} s</text>\
                 <rect class=\"bar\" x=\"{LABEL}\" y=\"{top:.1}\" width=\"{:.1}\" height=\"13\" fill=\"{colour}\"/>",
                top + 11.0,
                (seconds * scale).max(1.0),
            );
        }
    }
    let _ = writeln!(
        out,
        "<text x=\"4\" y=\"{:.1}\" font-size=\"12\">backswing:downswing you {:.1}:1, coach {:.1}:1</text>\
         <text x=\"4\" y=\"{:.1}\" font-size=\"12\">(tour players about 3:1, putts about 2:1)</text></svg>",
        height - 22.0,
        r.student_tempo_ratio,
        r.coach_tempo_ratio,
        height - 6.0,
    );
}

/// The DTW frame cost: the mean joint distance with the roots at the origin.
fn frame_cost(a: &[Vec3], b: &[Vec3]) -> f32 {
    let sum: f32 = a
        .iter()
        .zip(b)
        .map(|(p, q)| ((p - a[0]) - (q - b[0])).norm())
        .sum();
    sum / a.len().max(1) as f32
}

fn dtw(out: &mut String, n: usize, s: &Scored) {
    const SIZE: f32 = 360.0;
    const MARGIN: f32 = 40.0;
    /// Room on the right for the colour scale.
    const SCALE: f32 = 70.0;
    /// Steps of the colour scale.
    const STEPS: usize = 24;
    let (rows, cols) = (s.frames(&s.student), s.frames(&s.coach));
    let (cells_r, cells_c) = (rows.min(MATRIX_CELLS), cols.min(MATRIX_CELLS));
    let sample = |cell: usize, cells: usize, len: usize| (cell * len + len / 2) / cells.max(1);
    let costs: Vec<f32> = (0..cells_r * cells_c)
        .map(|c| {
            let (i, j) = (
                sample(c / cells_c, cells_r, rows),
                sample(c % cells_c, cells_c, cols),
            );
            frame_cost(s.frame(&s.student, i), s.frame(&s.coach, j))
        })
        .collect();
    let top = costs.iter().copied().fold(1e-6, f32::max);
    let shade = |cost: f32| (40.0 + 210.0 * (cost / top).max(0.0).sqrt()).min(250.0) as u8;
    let pixels: Vec<u8> = costs
        .iter()
        .flat_map(|&cost| [shade(cost), shade(cost), 255])
        .collect();
    let _ = writeln!(
        out,
        "<h3>Alignment</h3><p>Frame-to-frame distance (darker: closer poses) and the warping \
         path; lines mark the events (you across, coach down).</p>\
         <svg id=\"dtw-{n}\" width=\"{:.0}\" height=\"{:.0}\" viewBox=\"0 0 {:.0} {:.0}\">\
         <g transform=\"translate({MARGIN},10)\">\
         <image class=\"costs\" width=\"{SIZE}\" height=\"{SIZE}\" preserveAspectRatio=\"none\" \
         style=\"image-rendering:pixelated\" href=\"data:image/png;base64,{}\"/>",
        SIZE + MARGIN + SCALE,
        SIZE + MARGIN + 10.0,
        SIZE + MARGIN + SCALE,
        SIZE + MARGIN + 10.0,
        png_base64(&pixels, cells_c, cells_r)
    );
    // The colour scale: the mean joint distance each shade stands for, in cm.
    let (x, height) = (SIZE + 14.0, SIZE / STEPS as f32);
    for k in 0..STEPS {
        let cost = top * k as f32 / (STEPS - 1) as f32;
        let v = shade(cost);
        let _ = write!(
            out,
            "<rect class=\"scale\" x=\"{x:.1}\" y=\"{:.1}\" width=\"12\" height=\"{:.2}\" \
             fill=\"rgb({v},{v},255)\"/>",
            k as f32 * height,
            height + 0.5
        );
    }
    for share in [0.0, 0.25, 0.5, 1.0] {
        let _ = write!(
            out,
            "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"10\">{:.0} cm</text>",
            x + 15.0,
            (share * (SIZE - height) + height / 2.0 + 3.0),
            top * share * 100.0
        );
    }
    let (x_of, y_of) = (
        |j: usize| (j as f32 + 0.5) * SIZE / cols as f32,
        |i: usize| (i as f32 + 0.5) * SIZE / rows as f32,
    );
    // Ticks every half second of each swing.
    for (frames, hz, across) in [(cols, s.coach_hz, true), (rows, s.student_hz, false)] {
        let mut t = 0.0;
        while t * hz < frames as f32 {
            let at = t * hz;
            let (x1, y1, x2, y2, tx, ty, anchor) = if across {
                let x = x_of(at as usize);
                (x, SIZE, x, SIZE + 4.0, x, SIZE + 14.0, "middle")
            } else {
                let y = y_of(at as usize);
                (-4.0, y, 0.0, y, -6.0, y + 3.0, "end")
            };
            let _ = write!(
                out,
                "<line x1=\"{x1:.1}\" y1=\"{y1:.1}\" x2=\"{x2:.1}\" y2=\"{y2:.1}\" stroke=\"#555\"/>\
                 <text x=\"{tx:.1}\" y=\"{ty:.1}\" font-size=\"9\" text-anchor=\"{anchor}\">{t:.1}</text>"
            );
            t += 0.5;
        }
    }
    event_lines(out, &s.report.student_events, |i| {
        (0.0, y_of(i), SIZE, y_of(i), STUDENT)
    });
    event_lines(out, &s.report.coach_events, |j| {
        (x_of(j), 0.0, x_of(j), SIZE, COACH)
    });
    let points: Vec<String> = s
        .report
        .path
        .iter()
        .map(|&(i, j)| format!("{:.1},{:.1}", x_of(j as usize), y_of(i as usize)))
        .collect();
    let _ = writeln!(
        out,
        "<polyline class=\"path\" points=\"{}\" fill=\"none\" stroke=\"#ff9900\" stroke-width=\"2\"/>\
         <text x=\"{:.0}\" y=\"{:.0}\" font-size=\"12\" text-anchor=\"middle\">coach, seconds ({cols} frames)</text>\
         <text x=\"-30\" y=\"{:.0}\" font-size=\"12\" text-anchor=\"middle\" \
         transform=\"rotate(-90 -30 {:.0})\">you, seconds ({rows} frames)</text></g></svg>",
        points.join(" "),
        SIZE / 2.0,
        SIZE + 28.0,
        SIZE / 2.0,
        SIZE / 2.0
    );
}

/// An RGB image `width` × `height` as a base64 PNG.
fn png_base64(rgb: &[u8], width: usize, height: usize) -> String {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width as u32, height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    // Writing to memory fails only for a size that does not match the pixels, which the
    // caller's lengths rule out; an empty image then draws nothing.
    let written = encoder
        .write_header()
        .and_then(|mut writer| writer.write_image_data(rgb));
    match written {
        Ok(()) => base64::engine::general_purpose::STANDARD.encode(bytes),
        Err(_) => String::new(),
    }
}

fn event_lines(
    out: &mut String,
    events: &SwingEvents,
    line: impl Fn(usize) -> (f32, f32, f32, f32, &'static str),
) {
    for (_, f) in events.iter() {
        let (x1, y1, x2, y2, colour) = line(f);
        let _ = write!(
            out,
            "<line x1=\"{x1:.1}\" y1=\"{y1:.1}\" x2=\"{x2:.1}\" y2=\"{y2:.1}\" stroke=\"{colour}\" \
             stroke-width=\"0.8\" stroke-dasharray=\"4 3\"/>"
        );
    }
}

fn deviation(out: &mut String, n: usize, s: &Scored) {
    /// Rows for the events' names under the time axis.
    const LABEL_ROWS: usize = 3;
    /// Width of one character of a 9-pixel label, pixels (a generous mean).
    const LABEL_CHAR_WIDTH: f32 = 5.0;
    const WIDTH: f32 = 640.0;
    const HEIGHT: f32 = 220.0;
    const LEFT: f32 = 44.0;
    let (student_stance, coach_stance) = s.stances();
    let mut joints: Vec<(usize, Joint)> = Vec::new();
    for d in &s.report.spatial {
        if joints.len() < DEVIATION_JOINTS && !joints.iter().any(|&(_, j)| j == d.joint) {
            if let Some(k) = s.skeleton.index_of(d.joint) {
                joints.push((k, d.joint));
            }
        }
    }
    let frames = s.frames(&s.student);
    let series: Vec<Vec<f32>> = joints
        .iter()
        .map(|&(k, _)| {
            (0..frames)
                .map(|i| {
                    let a = student_stance.local(s.frame(&s.student, i)[k]);
                    let b = coach_stance.local(s.frame(&s.coach, s.matched(i))[k]);
                    (a - b).norm() * 100.0
                })
                .collect()
        })
        .collect();
    let top = series.iter().flatten().copied().fold(5.0, f32::max) * 1.1;
    let x_of = |i: usize| LEFT + i as f32 * (WIDTH - LEFT - 10.0) / frames.max(2) as f32;
    let y_of = |cm: f32| HEIGHT - 30.0 - cm / top * (HEIGHT - 52.0);
    let _ = writeln!(
        out,
        "<h3>Deviation over the swing</h3><p>How far your joints are from the virtual coach's \
         at the matched moment, in your stance frame (cm).</p>\
         <svg id=\"deviation-{n}\" width=\"{WIDTH}\" height=\"{HEIGHT}\" \
         viewBox=\"0 0 {WIDTH} {HEIGHT}\">"
    );
    for tick in [0.0, top / 2.0, top / 1.1] {
        let _ = write!(
            out,
            "<text x=\"4\" y=\"{:.1}\" font-size=\"10\">{tick:.0} cm</text>\
             <line x1=\"{LEFT}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"#ddd\"/>",
            y_of(tick) + 3.0,
            y_of(tick),
            WIDTH - 10.0,
            y_of(tick)
        );
    }
    // The tolerance: no joint is advised on within it (nor within 5 times its uncertainty).
    let tolerance = SPATIAL_THRESHOLD_M * 100.0;
    let _ = write!(
        out,
        "<line class=\"tolerance\" x1=\"{LEFT}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" \
         stroke=\"#444\" stroke-dasharray=\"6 3\"/><text x=\"{:.1}\" y=\"{:.1}\" font-size=\"9\" \
         text-anchor=\"end\">{tolerance:.0} cm: the least advised on</text>",
        WIDTH - 10.0,
        WIDTH - 12.0,
        y_of(tolerance) - 3.0,
        y = y_of(tolerance)
    );
    // Each event's name goes on the highest of the label rows where it overlaps no other.
    let mut row_ends = [f32::MIN; LABEL_ROWS];
    for (event, i) in s.report.student_events.iter() {
        let x = x_of(i);
        let name = event.name().replace('_', " ");
        let half = name.len() as f32 * LABEL_CHAR_WIDTH / 2.0;
        let row = (0..LABEL_ROWS)
            .find(|&r| row_ends[r] < x - half)
            .unwrap_or_else(|| {
                (0..LABEL_ROWS).fold(0, |a, r| if row_ends[r] < row_ends[a] { r } else { a })
            });
        row_ends[row] = x + half;
        let _ = write!(
            out,
            "<line x1=\"{x:.1}\" y1=\"10\" x2=\"{x:.1}\" y2=\"{:.1}\" stroke=\"#999\" stroke-dasharray=\"3 3\"/>\
             <text x=\"{x:.1}\" y=\"{:.1}\" font-size=\"9\" text-anchor=\"middle\">{name}</text>",
            HEIGHT - 30.0,
            HEIGHT - 20.0 + row as f32 * 9.0,
        );
    }
    for (row, ((_, joint), values)) in joints.iter().zip(&series).enumerate() {
        let points: Vec<String> = values
            .iter()
            .enumerate()
            .map(|(i, &v)| format!("{:.1},{:.1}", x_of(i), y_of(v)))
            .collect();
        let colour = PALETTE[row];
        let _ = write!(
            out,
            "<polyline class=\"joint-line\" points=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.6\"/>\
             <text x=\"{:.0}\" y=\"{:.0}\" font-size=\"11\" fill=\"{colour}\">{}</text>",
            points.join(" "),
            LEFT + 10.0 + row as f32 * 120.0,
            12.0,
            joint.name().replace('_', " ")
        );
    }
    if joints.is_empty() {
        let _ = write!(
            out,
            "<text x=\"{LEFT}\" y=\"40\" font-size=\"13\">Every joint within tolerance at every event.</text>"
        );
    }
    out.push_str("</svg>\n");
}

fn event_label(e: Event) -> String {
    capitalized(&e.name().replace('_', " "))
}

fn capitalized(s: &str) -> String {
    let mut chars = s.chars();
    chars
        .next()
        .map_or_else(String::new, |c| c.to_uppercase().chain(chars).collect())
}

/// `s` with the characters HTML gives meaning to escaped.
fn escape(s: &str) -> String {
    s.chars()
        .fold(String::with_capacity(s.len()), |mut out, c| {
            match c {
                '<' => out.push_str("&lt;"),
                '>' => out.push_str("&gt;"),
                '&' => out.push_str("&amp;"),
                '"' => out.push_str("&quot;"),
                _ => out.push(c),
            }
            out
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped() {
        assert_eq!(escape("<a & \"b\">"), "&lt;a &amp; &quot;b&quot;&gt;");
        let page = page("x<y", &["a&b".into()], None, &[]);
        assert!(page.contains("<title>x&lt;y</title>") && page.contains("a&amp;b"));
        assert!(page.contains("id=\"no-swing\""));
    }

    #[test]
    fn an_unscored_swing_says_why() {
        let swing = Swing {
            heading: "swing 1".into(),
            outcome: Err("no impact found".into()),
        };
        let page = page("t", &[], None, &[swing]);
        assert!(page.contains("id=\"swing-1\"") && page.contains("Not scored: no impact found"));
    }
}
