//! The places screen: one finished `unsupervised-places` run played back at a cursor time.
//!
//! Left, the map: walls grey, landmarks as stored (odometric place; colour = the stream whose
//! significant class made it: ART-1 yellow, growing K-means cyan, Fuzzy ART magenta; white once
//! matched), the truth white, the corrected estimate (compass + landmarks) green, wheels plus
//! compass heading blue, the plain odometry red, and the last second's match as a light-blue
//! jump. Right: the absolute error over time (the same colours, the thesis's bound of half a
//! diameter grey; the scale fits the corrected and compass errors, the plain odometry's tens
//! of diameters leave it at the top, its peak in the legend), the three class streams (one
//! glyph per label, the newest on the right) and the matches so far with the share of the way
//! each moved (its gain).
//!
//! Layer: presentation only; numbers come from the report, so nothing from outside reaches
//! the terminal as text. Cannot fail.

use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style, Stylize};
use ratatui::symbols::Marker;
use ratatui::text::{Line as TLine, Span};
use ratatui::widgets::canvas::{Canvas, Line, Points};
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Paragraph};
use ratatui::Frame;

use emulator::scenarios::unsupervised_places::{PlacesReport, World, DIAMETER_M, WRONG_OFFSET};

/// Colour of each class stream (ART-1, growing K-means, Fuzzy ART).
pub const STREAM_COLOURS: [Color; 3] = [Color::Yellow, Color::Cyan, Color::Magenta];
/// Stream names, in that order.
pub const STREAM_NAMES: [&str; 3] = ["ART-1", "K-means", "FuzzyART"];
/// The corrected odometry.
pub const CORRECTED: Color = Color::Green;
/// The plain odometry.
pub const PLAIN: Color = Color::LightRed;
/// Wheels plus compass heading, no landmarks.
pub const COMPASS: Color = Color::Blue;
/// The truth.
pub const TRUTH: Color = Color::White;

/// Glyphs for class labels 0..61; a label past them wraps (the colour tells them apart).
const GLYPHS: &[u8] = b"0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ";
const GLYPH_COLOURS: [Color; 6] = [
    Color::LightYellow,
    Color::LightCyan,
    Color::LightMagenta,
    Color::LightGreen,
    Color::LightBlue,
    Color::Gray,
];

/// A run and the playback cursor.
#[derive(Debug, Clone)]
pub struct PlacesView {
    report: PlacesReport,
    walls: Vec<[f64; 4]>,
    bounds: [f64; 4],
    t_s: f64,
}

impl PlacesView {
    /// The view of `report`, made in `world`, at time 0.
    pub fn new(report: PlacesReport, world: &World) -> Self {
        let walls: Vec<[f64; 4]> = world
            .walls
            .segments()
            .iter()
            .map(|s| [s.a.x, s.a.y, s.b.x, s.b.y])
            .collect();
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for w in &walls {
            b = [
                b[0].min(w[0]).min(w[2]),
                b[1].min(w[1]).min(w[3]),
                b[2].max(w[0]).max(w[2]),
                b[3].max(w[1]).max(w[3]),
            ];
        }
        if !b.iter().all(|v| v.is_finite()) {
            b = [0.0, 0.0, 1.0, 1.0];
        }
        Self {
            report,
            walls,
            bounds: b,
            t_s: 0.0,
        }
    }

    /// The cursor, simulated seconds.
    pub fn time(&self) -> f64 {
        self.t_s
    }

    /// Moves the cursor by `dt` seconds (clamped to the run).
    pub fn advance(&mut self, dt: f64) {
        self.seek(self.t_s + dt);
    }

    /// Puts the cursor at `t` seconds (clamped to the run).
    pub fn seek(&mut self, t: f64) {
        let t = if t.is_nan() { 0.0 } else { t };
        self.t_s = t.clamp(0.0, self.report.duration_s);
    }

    /// Series points up to the cursor.
    fn series_len(&self) -> usize {
        self.report.series.partition_point(|p| p.t_s <= self.t_s)
    }

    /// Matches up to the cursor.
    fn matches_len(&self) -> usize {
        self.report.match_log.partition_point(|m| m.t_s <= self.t_s)
    }

    /// Landmarks made by the cursor (landmark indices grow in time).
    fn landmarks_len(&self) -> usize {
        let n = self.series_len();
        let made = n
            .checked_sub(1)
            .map_or(0, |i| self.report.series[i].landmarks);
        made.min(self.report.landmark_positions.len())
    }

    /// The header line's text (tests read it).
    pub fn header(&self, speed: f64, paused: bool) -> String {
        let r = &self.report;
        let n = self.series_len();
        let (ec, eq, ep) = n.checked_sub(1).map_or((0.0, 0.0, 0.0), |i| {
            let p = &r.series[i];
            (p.corrected_err, p.compass_err, p.plain_err)
        });
        format!(
            "Mächler places · {:?} seed {} · t {:.0}/{:.0} s {} · landmarks {} · matches {} · \
             error corrected {:.2} compass {:.2} plain {:.2} diameters",
            r.arena,
            r.seed,
            self.t_s,
            r.duration_s,
            if paused {
                "paused".to_owned()
            } else {
                format!("x{speed}")
            },
            self.landmarks_len(),
            self.matches_len(),
            ec,
            eq,
            ep
        )
    }

    /// The last `width` labels of every stream up to the cursor, oldest first.
    pub fn stream_tail(&self, width: usize) -> [Vec<u8>; 3] {
        let cs = &self.report.class_streams;
        let period = self.report.period_s.max(1e-9);
        let end = ((self.t_s / period) as usize).min(cs.len());
        let start = end.saturating_sub(width);
        let mut out: [Vec<u8>; 3] = Default::default();
        for labels in &cs[start..end] {
            for (o, &l) in out.iter_mut().zip(labels) {
                o.push(l);
            }
        }
        out
    }
}

/// Draws `view` on the whole frame.
pub fn render(f: &mut Frame, view: &PlacesView, speed: f64, paused: bool) {
    let [head, body, keys] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Min(8),
        Constraint::Length(1),
    ])
    .areas(f.area());
    f.render_widget(Paragraph::new(view.header(speed, paused)).bold(), head);
    f.render_widget(
        Paragraph::new("space pause · ←/→ 10 s · Home/End · +/- speed · q quit").dark_gray(),
        keys,
    );
    let [map, side] =
        Layout::horizontal([Constraint::Percentage(50), Constraint::Percentage(50)]).areas(body);
    render_map(f, view, map);
    let [plot, streams, log] = Layout::vertical([
        Constraint::Percentage(45),
        Constraint::Length(5),
        Constraint::Min(3),
    ])
    .areas(side);
    render_errors(f, view, plot);
    render_streams(f, view, streams);
    render_matches(f, view, log);
}

fn render_map(f: &mut Frame, view: &PlacesView, area: Rect) {
    let r = &view.report;
    let n = view.series_len();
    let lm = view.landmarks_len();
    let matched: std::collections::HashSet<u16> = r.match_log[..view.matches_len()]
        .iter()
        .map(|m| m.landmark)
        .collect();
    let recent = r.match_log[..view.matches_len()]
        .last()
        .filter(|m| view.t_s - m.t_s <= 1.0);
    let [x0, y0, x1, y1] = view.bounds;
    let pad = DIAMETER_M;
    let canvas = Canvas::default()
        .block(
            Block::bordered()
                .title(" map: truth white · compass + landmarks green · compass blue · plain red "),
        )
        .marker(Marker::Braille)
        .x_bounds([x0 - pad, x1 + pad])
        .y_bounds([y0 - pad, y1 + pad])
        .paint(|ctx| {
            for w in &view.walls {
                ctx.draw(&Line::new(w[0], w[1], w[2], w[3], Color::DarkGray));
            }
            ctx.layer();
            let track =
                |pick: fn(&emulator::scenarios::unsupervised_places::SeriesPoint) -> [f64; 2]| {
                    r.series[..n]
                        .iter()
                        .map(|p| {
                            let q = pick(p);
                            (q[0], q[1])
                        })
                        .collect::<Vec<_>>()
                };
            let plain = track(|p| p.plain);
            let corrected = track(|p| p.corrected);
            let compass = track(|p| p.compass);
            let truth = track(|p| p.truth);
            ctx.draw(&Points::new(&plain, PLAIN));
            ctx.draw(&Points::new(&compass, COMPASS));
            ctx.draw(&Points::new(&corrected, CORRECTED));
            ctx.draw(&Points::new(&truth, TRUTH));
            ctx.layer();
            for (s, colour) in STREAM_COLOURS.iter().enumerate() {
                let pts: Vec<(f64, f64)> = r.landmark_positions[..lm]
                    .iter()
                    .enumerate()
                    .filter(|(i, p)| p[2] as usize == s && !matched.contains(&(*i as u16)))
                    .map(|(_, p)| (p[0], p[1]))
                    .collect();
                ctx.draw(&Points::new(&pts, *colour));
            }
            let hits: Vec<(f64, f64)> = r.landmark_positions[..lm]
                .iter()
                .enumerate()
                .filter(|(i, _)| matched.contains(&(*i as u16)))
                .map(|(_, p)| (p[0], p[1]))
                .collect();
            ctx.draw(&Points::new(&hits, Color::White));
            if let Some(m) = recent {
                ctx.draw(&Line::new(
                    m.from[0],
                    m.from[1],
                    m.to[0],
                    m.to[1],
                    Color::LightBlue,
                ));
            }
        });
    f.render_widget(canvas, area);
}

fn render_errors(f: &mut Frame, view: &PlacesView, area: Rect) {
    let r = &view.report;
    let n = view.series_len();
    let c: Vec<(f64, f64)> = r.series[..n]
        .iter()
        .map(|p| (p.t_s, p.corrected_err))
        .collect();
    let p: Vec<(f64, f64)> = r.series[..n].iter().map(|p| (p.t_s, p.plain_err)).collect();
    let q: Vec<(f64, f64)> = r.series[..n]
        .iter()
        .map(|p| (p.t_s, p.compass_err))
        .collect();
    let bound = [(0.0, 0.5), (r.duration_s, 0.5)];
    // Scaled to the two estimates that stay near the bound; the plain odometry (tens of
    // diameters) would flatten them, so it leaves the chart at the top.
    let top = r.compass_peak.max(r.corrected_peak).max(1.0).ceil();
    let plain_name = format!("plain (peak {:.1})", r.plain_peak);
    let chart = Chart::new(vec![
        Dataset::default()
            .name("bound 1/2")
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(Style::default().dark_gray())
            .data(&bound),
        Dataset::default()
            .name(plain_name)
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(Style::default().fg(PLAIN))
            .data(&p),
        Dataset::default()
            .name("compass")
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(Style::default().fg(COMPASS))
            .data(&q),
        Dataset::default()
            .name("compass + landmarks")
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(Style::default().fg(CORRECTED))
            .data(&c),
    ])
    .block(Block::bordered().title(" error, robot diameters "))
    // Four series: the default (a quarter of the chart) hides the legend on small panels.
    .hidden_legend_constraints((Constraint::Ratio(1, 2), Constraint::Ratio(3, 4)))
    .x_axis(
        Axis::default()
            .bounds([0.0, r.duration_s])
            .labels(["0 s".to_owned(), format!("{:.0} s", r.duration_s)]),
    )
    .y_axis(
        Axis::default()
            .bounds([0.0, top])
            .labels(["0".to_owned(), format!("{top:.0}")]),
    );
    f.render_widget(chart, area);
}

fn render_streams(f: &mut Frame, view: &PlacesView, area: Rect) {
    let width = usize::from(area.width.saturating_sub(12));
    let tails = view.stream_tail(width);
    let lines: Vec<TLine> = tails
        .iter()
        .enumerate()
        .map(|(s, tail)| {
            let mut spans = vec![Span::styled(
                format!("{:<9} ", STREAM_NAMES[s]),
                Style::default().fg(STREAM_COLOURS[s]),
            )];
            spans.extend(tail.iter().map(|&l| {
                let g = GLYPHS[usize::from(l) % GLYPHS.len()] as char;
                Span::styled(
                    g.to_string(),
                    Style::default().fg(GLYPH_COLOURS[usize::from(l) % GLYPH_COLOURS.len()]),
                )
            }));
            TLine::from(spans)
        })
        .collect();
    f.render_widget(
        Paragraph::new(lines).block(Block::bordered().title(" class streams (newest right) ")),
        area,
    );
}

fn render_matches(f: &mut Frame, view: &PlacesView, area: Rect) {
    let log = &view.report.match_log[..view.matches_len()];
    let rows = usize::from(area.height.saturating_sub(2));
    let lines: Vec<TLine> = log
        .iter()
        .rev()
        .take(rows)
        .map(|m| {
            let better = m.err_after <= m.err_before;
            // The truth's verdict on the identification itself (§3.15.2: identical landmarks
            // closer than half a diameter cannot be told apart; farther is another place).
            let wrong = m.offset > WRONG_OFFSET;
            TLine::from(vec![
                Span::raw(format!(
                    "{:7.1} s  landmark {:>3}  D {:.2} gain {:.2} moved {:.2} ",
                    m.t_s, m.landmark, m.d, m.gain, m.correction
                )),
                Span::styled(
                    format!("off {:.2}{}", m.offset, if wrong { "!" } else { "" }),
                    Style::default().fg(if wrong { Color::Red } else { Color::Reset }),
                ),
                Span::raw(format!(" err {:.2}->", m.err_before)),
                Span::styled(
                    format!("{:.2}", m.err_after),
                    Style::default().fg(if better { Color::Green } else { Color::Red }),
                ),
            ])
        })
        .collect();
    let title = format!(
        " matches ({}; newest first) off: from the landmark's true place, ! wrong place ",
        log.len()
    );
    f.render_widget(
        Paragraph::new(lines).block(Block::bordered().title(title)),
        area,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use emulator::scenarios::unsupervised_places::{generate, run, ArenaKind, PlacesOptions};
    use ratatui::backend::TestBackend;
    use ratatui::Terminal;

    fn view() -> PlacesView {
        let mut o = PlacesOptions::new(ArenaKind::Unstructured, 4);
        o.duration_s = 240.0;
        o.record_labels = true;
        o.series_every_s = 0.2;
        let r = run(&o);
        PlacesView::new(r, &generate(o.arena, o.seed, o.lamps))
    }

    fn screen(v: &PlacesView) -> String {
        let mut t = Terminal::new(TestBackend::new(160, 40)).unwrap();
        t.draw(|f| render(f, v, 20.0, false)).unwrap();
        let buf = t.backend().buffer().clone();
        let mut s = String::new();
        for y in 0..buf.area.height {
            for x in 0..buf.area.width {
                s.push_str(buf[(x, y)].symbol());
            }
            s.push('\n');
        }
        s
    }

    #[test]
    fn playback_shows_landmarks_matches_and_streams_as_they_happen() {
        let mut v = view();
        let (lms, matches) = (v.report.landmarks, v.report.matches);
        assert!(matches > 0, "seed 4 matches in its first 240 s");
        let start = screen(&v);
        assert!(start.contains("landmarks 0 · matches 0"), "{start}");
        assert!(start.contains("matches (0; newest first)"), "{start}");
        v.seek(f64::INFINITY);
        let end = screen(&v);
        assert!(
            end.contains(&format!("landmarks {lms} · matches {matches}")),
            "{end}"
        );
        assert!(
            end.contains(&format!("matches ({matches}; newest first)")),
            "{end}"
        );
        // The newest match is listed with its time and landmark.
        let m = v.report.match_log.last().unwrap();
        assert!(
            end.contains(&format!("{:7.1} s  landmark {:>3}", m.t_s, m.landmark)),
            "{end}"
        );
        for name in STREAM_NAMES {
            assert!(end.contains(name), "{name}: {end}");
        }
        // All three estimates against the truth: in the header, the legend and the match log.
        let last = v.report.series.last().unwrap();
        assert!(
            end.contains(&format!(
                "error corrected {:.2} compass {:.2} plain {:.2} diameters",
                last.corrected_err, last.compass_err, last.plain_err
            )),
            "{end}"
        );
        for legend in ["compass + landmarks", "compass", "plain (peak"] {
            assert!(end.contains(legend), "{legend}: {end}");
        }
        assert!(end.contains(&format!("gain {:.2}", m.gain)), "{end}");
        // ... and the truth's verdict on the identification.
        let mark = if m.offset > WRONG_OFFSET { "!" } else { "" };
        assert!(
            end.contains(&format!(
                "off {:.2}{mark} err {:.2}->{:.2}",
                m.offset, m.err_before, m.err_after
            )),
            "{end}"
        );
        // The stream rows hold the labels up to the cursor, the newest last.
        let tail = v.stream_tail(10);
        let last = v.report.class_streams.last().unwrap();
        for s in 0..3 {
            assert_eq!(tail[s].len(), 10);
            assert_eq!(tail[s][9], last[s]);
        }
    }

    #[test]
    fn the_cursor_stays_in_the_run() {
        let mut v = view();
        v.advance(-5.0);
        assert_eq!(v.time(), 0.0);
        v.seek(f64::NAN);
        assert_eq!(v.time(), 0.0);
        v.advance(1e9);
        assert_eq!(v.time(), 240.0);
    }
}
