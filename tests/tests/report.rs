//! The HTML report: written by `score --report`, `replay --report` and `demo`, complete and
//! self-contained, opening with the range session where it holds several swings, and rendered
//! by headless Chromium into a screenshot that shows the student and the coach.

use posecoach_cli::{demo, replay, score, synth};
use posecoach_tests::parse;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A folder of its own for a test.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("posecoach-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn fixture(name: &str) -> String {
    posecoach_tests::fixture(name).display().to_string()
}

/// The page `score --report` writes for the iron against the driver.
fn scored_page(dir: &Path) -> PathBuf {
    let page = dir.join("report.html");
    let (coach, student) = (
        fixture("golf_driver_60hz.csv"),
        fixture("golf_iron_60hz.csv"),
    );
    let out = page.display().to_string();
    let args: score::Args = parse(&["--coach", &coach, "--student", &student, "--report", &out]);
    score::run(&args).unwrap();
    page
}

/// The page `score --report` writes for the iron, the driver and the iron again against the
/// driver (a range session of three swings), and the JSON `--json` prints for it.
fn session_page(dir: &Path) -> (PathBuf, Value) {
    let page = dir.join("session.html");
    let (coach, iron) = (
        fixture("golf_driver_60hz.csv"),
        fixture("golf_iron_60hz.csv"),
    );
    let out = page.display().to_string();
    let args: score::Args = parse(&[
        "--coach",
        &coach,
        "--student",
        &iron,
        "--student",
        &coach,
        "--student",
        &iron,
        "--report",
        &out,
        "--json",
    ]);
    let json = serde_json::from_str(&score::run(&args).unwrap()).unwrap();
    (page, json)
}

/// Each body-level metric's name (as the session's text names it) in a swing's `report` JSON.
fn metrics(report: &Value) -> Vec<String> {
    let names = |list: &Value, name: &dyn Fn(&Value) -> String| -> Vec<String> {
        list.as_array().unwrap().iter().map(name).collect()
    };
    let text = |v: &Value| v.as_str().unwrap().to_string();
    let mut out = names(&report["tempo"]["phases"], &|p| text(&p["phase"]));
    out.push("pause".to_string());
    out.extend(names(&report["body_checks"], &|c| {
        format!(
            "{}_{}",
            text(&c["measure"]),
            text(&c["position"]).to_lowercase()
        )
    }));
    out.extend(names(&report["kinematic_sequence"]["gaps"], &|g| {
        format!("{}_{}_gap", text(&g["first"]), text(&g["then"]))
    }));
    out
}

/// `page` opens with its range session as `json` (its command's `--json`) has it: the
/// tendencies in order or the open question, the swings set aside, the consistency, and a
/// small multiple for each body-level metric with a dot for each of the session's swings
/// measured in it.
fn check_session(page: &str, json: &Value) {
    let at = page.find("<section id=\"session\"").expect("the session");
    assert!(
        at < page.find("id=\"swing-1\"").unwrap(),
        "the session first"
    );
    let section = &page[at..at + page[at..].find("</section>").unwrap()];
    let session = &json["session"];
    let advice = session["advice"].as_array().unwrap();
    if advice.is_empty() {
        assert!(section.contains("<p id=\"open\">Nothing is clear yet"));
        if let Some(more) = session["open"]["more_swings"].as_u64() {
            assert!(section.contains(&format!("about {more} more swings")));
        }
    } else {
        let list = &section[section.find("<ol id=\"tendencies\">").unwrap()..];
        let list = &list[..list.find("</ol>").unwrap()];
        let items: Vec<&str> = list
            .split("<li>")
            .skip(1)
            .map(|i| &i[..i.find("</li>").unwrap()])
            .collect();
        let told: Vec<&str> = advice.iter().map(|a| a.as_str().unwrap()).collect();
        assert_eq!(items, told);
    }
    let set_aside = session["set_aside"].as_array().unwrap().len();
    assert_eq!(section.contains("id=\"set-aside\""), set_aside > 0);
    assert!(section.contains("id=\"consistency\"") && section.contains("0.02 s"));
    // The session's swings: the last it heard among those scored.
    let reports: Vec<&Value> = json["swings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|s| s.get("report"))
        .collect();
    let heard = &reports[reports.len() - session["swings"].as_u64().unwrap() as usize..];
    let mut charts = Vec::new();
    for name in heard.iter().flat_map(|r| metrics(r)) {
        if !charts.contains(&name) {
            charts.push(name);
        }
    }
    assert_eq!(
        section.matches("<svg class=\"multiple\"").count(),
        charts.len()
    );
    for name in &charts {
        let at = section
            .find(&format!("id=\"multiple-{name}\""))
            .unwrap_or_else(|| panic!("{name}'s chart"));
        let chart = &section[at..at + section[at..].find("</svg>").unwrap()];
        let measured = heard.iter().filter(|r| metrics(r).contains(name)).count();
        assert_eq!(chart.matches("class=\"swing").count(), measured, "{name}");
        assert_eq!(chart.matches("class=\"coach\"").count(), 1, "{name}");
    }
}

/// Every part of swing `n` is on `page`, with a pose drawing per event and view.
fn check_parts(page: &str, n: usize, events: usize) {
    for part in [
        "score",
        "advice",
        "poses",
        "body",
        "sequence",
        "tempo",
        "dtw",
        "deviation",
    ] {
        assert!(page.contains(&format!("id=\"{part}-{n}\"")), "{part}-{n}");
    }
    let section = &page[page.find(&format!("id=\"swing-{n}\"")).unwrap()..];
    let section = &section[..section.find("</section>").unwrap()];
    assert_eq!(section.matches("class=\"pose-svg\"").count(), 2 * events);
    // Each pose figure stands on its ground line.
    assert_eq!(section.matches("class=\"ground\"").count(), 2 * events);
    // A row per P-position: the events and, in a full swing, P6 and P9 where found.
    let body = &section[section.find("id=\"body-").unwrap()..];
    let rows = body[..body.find("</table>").unwrap()]
        .matches("<tr><th>P")
        .count();
    assert!(
        rows >= events && rows <= events + 2,
        "{rows} rows for {events} events"
    );
    // The student's values carry their uncertainty, and the page says what "±" means.
    let table = &body[..body.find("</table>").unwrap()];
    assert!(table.matches(" &#177; ").count() + table.matches(" ± ").count() >= rows);
    assert!(section.contains("± is one standard deviation"));
    let sequence = &section[section.find("id=\"sequence-").unwrap()..];
    let sequence = &sequence[..sequence.find("</ul>").unwrap()];
    assert_eq!(
        sequence.matches("<li>").count(),
        if events == 8 { 2 } else { 0 }
    );
    // And the gaps between peaks both swings could be timed.
    assert!(sequence.matches("<li class=\"gap\">").count() <= if events == 8 { 2 } else { 0 });
    // The sequence's graph, for a full swing: per swing a curve and a peak for each link
    // (three without a club, four with one).
    let chart = section.find(&format!("id=\"sequence-chart-{n}\""));
    assert_eq!(chart.is_some(), events == 8);
    if let Some(at) = chart {
        let chart = &section[at..at + section[at..].find("</svg>").unwrap()];
        let curves = chart.matches("<polyline").count();
        assert!(curves == 6 || curves == 8, "{curves} curves");
        assert_eq!(chart.matches("class=\"peak\"").count(), curves);
    }
    assert!(
        section.contains("class=\"tolerance\""),
        "the deviation chart's tolerance"
    );
    assert!(
        section.contains("data:image/png;base64,"),
        "the cost matrix"
    );
    assert!(section.contains("class=\"path\""), "the warping path");
    assert_eq!(
        section.matches("class=\"scale\"").count(),
        24,
        "the cost matrix's colour scale"
    );
}

#[test]
fn score_writes_a_self_contained_page_with_every_part() {
    let dir = scratch("report-score");
    let page = std::fs::read_to_string(scored_page(&dir)).unwrap();
    check_parts(&page, 1, 8);
    // One swing alone: no session.
    assert!(!page.contains("id=\"session\""));
    // The club is tracked here: the ball lies where its head rested, in every figure; the
    // joints the advice names are ringed at their events, in both views.
    assert_eq!(page.matches("class=\"ball\"").count(), 16);
    for external in ["http:", "https:", "<script", "src=\""] {
        assert!(!page.contains(external), "{external}");
    }
    // A JSON name still gets the JSON report.
    let json = dir.join("report.json").display().to_string();
    let (coach, student) = (
        fixture("golf_driver_60hz.csv"),
        fixture("golf_iron_60hz.csv"),
    );
    let args: score::Args = parse(&["--coach", &coach, "--student", &student, "--report", &json]);
    score::run(&args).unwrap();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(report["score"].as_f64().is_some());
    let advised = report["spatial"].as_array().unwrap().len();
    assert!(advised > 0);
    assert_eq!(page.matches("class=\"advised\"").count(), 2 * advised);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn replay_and_demo_pages_hold_every_swing_of_the_session() {
    let dir = scratch("report-replay");
    let page = dir.join("session.html").display().to_string();
    let log = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("logs/short_cmu_30hz.pclog");
    let log = log.display().to_string();
    let args: replay::Args = parse(&[&log, "--report", &page, "--json"]);
    let replayed: serde_json::Value = serde_json::from_str(&replay::run(&args).unwrap()).unwrap();
    let page = std::fs::read_to_string(&page).unwrap();
    // Two swings, the session the second's alone: it has a new coach.
    check_session(&page, &replayed);
    let swings = replayed["swings"].as_array().unwrap();
    assert!(!swings.is_empty());
    for (i, swing) in swings.iter().enumerate() {
        match swing.get("report") {
            Some(report) => {
                let events = report["events"]["student"].as_object().unwrap().len();
                check_parts(&page, i + 1, events);
            }
            None => assert!(page.contains("Not scored:")),
        }
    }
    // The demo replays the same bundled session: the same page and the same JSON.
    let out = dir.join("demo").display().to_string();
    let text = demo::run(&parse::<demo::Args>(&["--out-dir", &out])).unwrap();
    assert!(
        text.contains("advice") && text.contains("report.html"),
        "{text}"
    );
    let demo_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("demo/report.json")).unwrap())
            .unwrap();
    assert_eq!(demo_json, replayed);
    let demo_page = std::fs::read_to_string(dir.join("demo/report.html")).unwrap();
    let body = |p: &str| p[p.find("<section").unwrap()..].to_string();
    assert_eq!(body(&demo_page), body(&page));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_page_of_several_swings_opens_with_their_range_session() {
    let dir = scratch("report-session");
    // Three students scored against one coach: nothing clear yet.
    let (page, json) = session_page(&dir);
    let page = std::fs::read_to_string(page).unwrap();
    check_session(&page, &json);
    for n in 1..=3 {
        check_parts(&page, n, 8);
    }
    // A range session whose backswings are all 1.3 times the coach's: its tendency first.
    let log = dir.join("range.pclog").display().to_string();
    let driver = fixture("golf_driver_60hz.csv");
    let synth: synth::Args = parse(&[
        "--swing",
        &driver,
        "--swing",
        &driver,
        "--swing",
        &driver,
        "--backswing-tempo",
        "1.3",
        "--coach",
        "0",
        "--seed",
        "3",
        "--out",
        &log,
    ]);
    synth::run(&synth).unwrap();
    let out = dir.join("range.html").display().to_string();
    let replayed: Value = serde_json::from_str(
        &replay::run(&parse::<replay::Args>(&[&log, "--report", &out, "--json"])).unwrap(),
    )
    .unwrap();
    assert!(!replayed["session"]["advice"].as_array().unwrap().is_empty());
    check_session(&std::fs::read_to_string(&out).unwrap(), &replayed);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Headless Chromium: `$POSECOACH_CHROMIUM`, else the first of the usual names on the path.
fn chromium() -> Option<PathBuf> {
    if let Some(path) = std::env::var_os("POSECOACH_CHROMIUM") {
        return Some(PathBuf::from(path));
    }
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .find(|name| {
            Command::new(name)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .map(PathBuf::from)
}

fn headless(browser: &Path, dir: &Path) -> Command {
    let mut command = Command::new(browser);
    command.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--no-first-run",
        "--hide-scrollbars",
        "--window-size=1280,2400",
    ]);
    command.arg(format!("--user-data-dir={}", dir.join("profile").display()));
    command
}

/// Pixels of `rgb` within `tolerance` of `colour` on each channel.
fn count(rgb: &[u8], colour: [u8; 3], tolerance: u8) -> usize {
    rgb.chunks_exact(3)
        .filter(|p| (0..3).all(|c| p[c].abs_diff(colour[c]) <= tolerance))
        .count()
}

#[test]
fn chromium_renders_the_report() {
    let Some(browser) = chromium() else {
        eprintln!(
            "chromium_renders_the_report: skipped: no chromium found (install Debian's \
             `chromium` or set POSECOACH_CHROMIUM); ci.sh installs it where it can"
        );
        return;
    };
    let dir = scratch("report-chromium");
    let page = scored_page(&dir);
    let url = format!("file://{}", page.display());
    // The DOM as Chromium parsed it: every part is there.
    let dom = headless(&browser, &dir)
        .arg("--dump-dom")
        .arg(&url)
        .output()
        .unwrap();
    assert!(
        dom.status.success(),
        "{}",
        String::from_utf8_lossy(&dom.stderr)
    );
    check_parts(&String::from_utf8_lossy(&dom.stdout), 1, 8);
    // The screenshot: a page with the student in blue and the coach in vermillion on it.
    let shot = dir.join("shot.png");
    let status = headless(&browser, &dir)
        .arg(format!("--screenshot={}", shot.display()))
        .arg(&url)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    let channels = info.color_type.samples();
    let rgb: Vec<u8> = pixels[..info.buffer_size()]
        .chunks_exact(channels)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let total = rgb.len() / 3;
    let white = count(&rgb, [255, 255, 255], 8);
    assert!(
        white < total * 95 / 100,
        "blank: {white} of {total} pixels white"
    );
    let (blue, vermillion) = (
        count(&rgb, [0, 114, 178], 40),
        count(&rgb, [213, 94, 0], 40),
    );
    eprintln!("screenshot {total} pixels: {blue} student blue, {vermillion} coach vermillion");
    assert!(
        blue > 500 && vermillion > 500,
        "blue {blue}, vermillion {vermillion}"
    );
    // On a phone's 390 px and a desktop's 1280 px, nothing is wider than the screen.
    for width in [390, 1280] {
        let (laid, _) = laid_out(&browser, &dir, &page, width);
        assert!(laid <= width, "{laid} px wide in a {width} px screen");
    }
    // A session's page too, and its charts' text as large as a phone needs.
    let (session, json) = session_page(&dir);
    let dom = headless(&browser, &dir)
        .arg("--dump-dom")
        .arg(format!("file://{}", session.display()))
        .output()
        .unwrap();
    check_session(&String::from_utf8_lossy(&dom.stdout), &json);
    for width in [390, 1280] {
        let (laid, least) = laid_out(&browser, &dir, &session, width);
        assert!(
            laid <= width,
            "the session: {laid} px wide in a {width} px screen"
        );
        assert!(
            least >= 11.0,
            "the session's charts: {least} px text at {width} px"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Beside the page in a frame, after it loads: the width it laid out to and its session's
/// smallest chart text, CSS px as drawn (very large where it has no session).
const PROBE: &str = "window.addEventListener('load', function () { \
    var page = document.getElementById('page').contentDocument, least = 1e9; \
    page.querySelectorAll('#session svg').forEach(function (svg) { \
      var scale = svg.getBoundingClientRect().width / svg.viewBox.baseVal.width; \
      svg.querySelectorAll('text, tspan').forEach(function (t) { \
        least = Math.min(least, parseFloat(getComputedStyle(t).fontSize) * scale); }); }); \
    document.body.setAttribute('data-laid-out', page.documentElement.scrollWidth); \
    document.body.setAttribute('data-least-font', least); });";

/// How `page` lays out on a screen `width` px wide: its width and its session's smallest chart
/// text, px. Headless Chromium's window is at least 500 px wide, so the page (which has no
/// scripts of its own) goes into a frame of that width, and [`PROBE`] beside it writes what it
/// measured into the DOM.
fn laid_out(browser: &Path, dir: &Path, page: &Path, width: u32) -> (u32, f32) {
    let html = std::fs::read_to_string(page).unwrap();
    let quoted = html
        .replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    let probe = dir.join(format!("probe-{width}.html"));
    let wrapper = format!(
        "<!DOCTYPE html><html><body style=\"margin:0\"><iframe id=\"page\" \
         style=\"width:{width}px;height:2400px;border:0\" srcdoc=\"{quoted}\"></iframe>\
         <script>{PROBE}</script></body></html>"
    );
    std::fs::write(&probe, wrapper).unwrap();
    let dom = headless(browser, dir)
        .arg("--dump-dom")
        .arg(format!("file://{}", probe.display()))
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&dom.stdout);
    let attribute = |name: &str| -> String {
        let at = dom.find(&format!("{name}=\"")).expect("the probe ran") + name.len() + 2;
        dom[at..at + dom[at..].find('"').unwrap()].to_string()
    };
    (
        attribute("data-laid-out").parse().unwrap(),
        attribute("data-least-font").parse().unwrap(),
    )
}
