//! The sensor panel: IR and light bars around a robot glyph, and every other reading as text.
//!
//! Layer: presentation. The glyph is a ratatui `Canvas` with the robot facing up: each IR
//! sensor is a bar pointing out from the body at its mounting angle (from the firmware's
//! profile, so it matches the robot), as long as its reading; ambient light is a tick on an
//! outer ring, longer when brighter (the wire's light values are inverted: lower is brighter).
//! Readings a robot lacks (see its capabilities) are shown as "—".

use protocol::{behaviours, caps, flags, ProfileId};
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style, Stylize};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::canvas::{Canvas, Circle, Context, Line as CLine};
use ratatui::widgets::{Block, Paragraph};
use ratatui::Frame;
use robot_firmware::profile::{IrLayout, Profile, ALICE, KHEPERA, MICRO_RATO};

use crate::app::{mode_name, App};

/// Radius of the body, IR bar room and light ring, in glyph units.
pub(super) const BODY: f64 = 1.0;
const IR_LEN: f64 = 1.6;
pub(super) const RING: f64 = 3.0;
const LIGHT_LEN: f64 = 0.5;

pub fn render(app: &App, frame: &mut Frame, area: Rect) {
    let profile = profile_of(app);
    // The glyph needs some layout before a robot says which it is; the title does not guess.
    let title = match app.peer {
        Some(_) => format!(" Sensors — {} ", profile.name),
        None => " Sensors ".to_string(),
    };
    let stale = app.stale_s();
    let mut block = Block::bordered().title(title);
    if let Some(age) = stale {
        // Old readings look like old readings: marked in words, and greyed below.
        block = block.title_top(
            Line::from(Span::styled(
                format!(" stale {age} s: no telemetry "),
                Style::new().fg(Color::Black).bg(Color::DarkGray),
            ))
            .right_aligned(),
        );
    }
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let beside = Layout::horizontal([Constraint::Percentage(40), Constraint::Percentage(60)]);
    let wide = inner.width >= 70;
    let text_w = if wide {
        let [_, t] = beside.areas(inner);
        t.width
    } else {
        inner.width
    };
    let mut lines = text_lines(app, profile, text_w);
    if stale.is_some() {
        for line in &mut lines {
            for span in &mut line.spans {
                span.style = Style::new().fg(Color::DarkGray);
            }
        }
    }
    let text_h = lines.len() as u16;
    let (glyph, text) = if wide {
        let [g, t] = beside.areas(inner);
        (g, t)
    } else {
        let [g, t] =
            Layout::vertical([Constraint::Min(5), Constraint::Length(text_h)]).areas(inner);
        (g, t)
    };
    if glyph.height >= 5 && profile.id == ProfileId::Alice {
        super::alice_sensors::render_glyph(app, frame, glyph);
    } else if glyph.height >= 5 {
        render_glyph(app, profile, frame, glyph);
    }
    frame.render_widget(Paragraph::new(lines), text);
}

/// The profile the robot said it is (Khepera before the handshake).
pub fn profile_of(app: &App) -> &'static Profile {
    match app.peer.as_ref().map(|p| p.profile) {
        Some(ProfileId::MicroRato) => &MICRO_RATO,
        Some(ProfileId::Alice) => &ALICE,
        _ => &KHEPERA,
    }
}

/// The glyph canvas's half extents in its units for `area`: the ring and a margin high, and
/// as wide as keeps circles round (Braille dots are 2 x 4 per cell).
pub(super) fn glyph_bounds(area: Rect) -> (f64, f64) {
    let half_y = RING + 0.3;
    (
        half_y * f64::from(area.width) / (2.0 * f64::from(area.height)),
        half_y,
    )
}

/// The robot's body and heading in a sensor glyph: a circle facing up. Every profile's glyph
/// (the IR and light ring here, ALICE's whiskers and photoresistors) draws the same body.
pub(super) fn draw_body(ctx: &mut Context<'_>) {
    ctx.draw(&Circle {
        x: 0.0,
        y: 0.0,
        radius: BODY,
        color: Color::White,
    });
    ctx.draw(&CLine {
        x1: 0.0,
        y1: 0.0,
        x2: 0.0,
        y2: BODY * 0.8,
        color: Color::White,
    });
}

fn render_glyph(app: &App, profile: &'static Profile, frame: &mut Frame, area: Rect) {
    let (half_x, half_y) = glyph_bounds(area);
    let t = app.telemetry;
    let has_light = app.peer.as_ref().is_none_or(|p| p.has(caps::AMBIENT_LIGHT));
    // Old readings in grey, like the text beside them.
    let stale = app.stale_s().is_some();
    let tint = move |c: Color| if stale { Color::DarkGray } else { c };
    let canvas = Canvas::default()
        .marker(Marker::Braille)
        .x_bounds([-half_x, half_x])
        .y_bounds([-half_y, half_y])
        .paint(move |ctx| {
            draw_body(ctx);
            let Some(t) = t else { return };
            ctx.layer();
            for (a, v) in sensor_angles(&profile.ir).zip(t.ir.values()) {
                let frac = f64::from(v) / 1023.0;
                let (dx, dy) = direction(a);
                ctx.draw(&CLine {
                    x1: dx * (BODY + 0.1),
                    y1: dy * (BODY + 0.1),
                    x2: dx * (BODY + 0.1 + 0.05 + IR_LEN * frac),
                    y2: dy * (BODY + 0.1 + 0.05 + IR_LEN * frac),
                    color: tint(heat(frac)),
                });
            }
            if has_light {
                ctx.layer();
                for (a, v) in sensor_angles(&KHEPERA.ir).zip(t.light.values()) {
                    let bright = 1.0 - f64::from(v.min(1023)) / 1023.0;
                    let (dx, dy) = direction(a);
                    ctx.draw(&CLine {
                        x1: dx * RING,
                        y1: dy * RING,
                        x2: dx * (RING - 0.05 - LIGHT_LEN * bright),
                        y2: dy * (RING - 0.05 - LIGHT_LEN * bright),
                        color: tint(Color::Yellow),
                    });
                }
            }
        });
    frame.render_widget(canvas, area);
}

/// Mounting angles of the sensors in use, radians from the heading (left positive).
fn sensor_angles(ir: &IrLayout) -> impl Iterator<Item = f64> + '_ {
    ir.angle_rad.iter().take(ir.count).map(|&a| f64::from(a))
}

/// Unit vector on screen for a sensor at `a` from a heading that points up.
fn direction(a: f64) -> (f64, f64) {
    let screen = std::f64::consts::FRAC_PI_2 + a;
    (screen.cos(), screen.sin())
}

fn heat(frac: f64) -> Color {
    if frac > 0.66 {
        Color::Red
    } else if frac > 0.33 {
        Color::Yellow
    } else {
        Color::Green
    }
}

/// A line of readings as groups ("pose ..", "σ .."): a narrow panel breaks a line between
/// groups rather than cutting it off.
type Row = Vec<Vec<Span<'static>>>;

/// Lays `rows` out in `width` columns: groups `gap` spaces apart (the flags' row one, others
/// two), a group that does not fit starting a new line (a group wider than the panel is cut,
/// as it would be anyway).
fn fit(rows: Vec<(usize, Row)>, width: u16) -> Vec<Line<'static>> {
    let width = usize::from(width);
    let mut out = Vec::new();
    for (gap, row) in rows {
        let mut line: Vec<Span<'static>> = Vec::new();
        let mut used = 0;
        for group in row {
            let w: usize = group.iter().map(Span::width).sum();
            if !line.is_empty() && used + gap + w > width {
                out.push(Line::from(std::mem::take(&mut line)));
                used = 0;
            }
            if !line.is_empty() {
                line.push(Span::raw(" ".repeat(gap)));
                used += gap;
            }
            line.extend(group);
            used += w;
        }
        out.push(Line::from(line));
    }
    out
}

fn text_lines(app: &App, profile: &Profile, width: u16) -> Vec<Line<'static>> {
    let Some(t) = app.telemetry else {
        return vec![Line::from("no telemetry yet".dark_gray())];
    };
    let has = |c: u32| app.peer.as_ref().map_or(profile.has(c), |p| p.has(c));
    let dim = Style::new().fg(Color::DarkGray);
    let label = |s: &'static str| Span::styled(s, dim);
    let deg = |mrad: i16| f64::from(mrad) / 1000.0 * 180.0 / std::f64::consts::PI;
    let rows: Vec<Row> = vec![
        vec![
            vec![
                label("pose "),
                Span::raw(format!(
                    "{:.3} {:.3} m {:.1}°",
                    f64::from(t.pose.x_mm) / 1000.0,
                    f64::from(t.pose.y_mm) / 1000.0,
                    deg(t.pose.heading_mrad)
                )),
            ],
            vec![
                label("σ "),
                Span::raw(format!(
                    "{} mm {:.1}°",
                    t.sigma.xy_mm,
                    deg(t.sigma.heading_mrad as i16)
                )),
            ],
        ],
        vec![
            vec![
                label("mode "),
                Span::styled(mode_name(t.mode), Style::new().fg(Color::Cyan).bold()),
            ],
            vec![
                label("behaviours "),
                Span::raw(behaviour_names(t.behaviour.active)),
            ],
        ],
        vec![
            vec![
                label("wheels "),
                Span::raw(format!(
                    "{} {} mm/s",
                    t.wheels.speed_mm_s[0], t.wheels.speed_mm_s[1]
                )),
            ],
            vec![
                label("motor "),
                Span::raw(format!(
                    "{} {}",
                    t.behaviour.motor_mm_s[0], t.behaviour.motor_mm_s[1]
                )),
            ],
        ],
    ];
    let enc = if has(caps::ENCODERS) {
        format!("{} {}", app.encoders.total[0], app.encoders.total[1])
    } else {
        "—".into()
    };
    let compass = if has(caps::COMPASS) {
        format!("{:.1}°", f64::from(t.compass_ddeg) / 10.0)
    } else {
        "—".into()
    };
    let mut rows: Vec<(usize, Row)> = rows.into_iter().map(|r| (2, r)).collect();
    rows.push((
        2,
        vec![
            vec![label("encoders "), Span::raw(enc)],
            vec![label("compass "), Span::raw(compass)],
        ],
    ));
    let battery = if has(caps::BATTERY) {
        format!("{} mV", t.battery_mv)
    } else {
        "—".into()
    };
    let beacon = if has(caps::BEACON) {
        if t.beacon.strength == 0 {
            "not seen".into()
        } else {
            format!(
                "{:+.1}° strength {}",
                f64::from(t.beacon.bearing_ddeg) / 10.0,
                t.beacon.strength
            )
        }
    } else {
        "—".into()
    };
    rows.push((
        2,
        vec![
            vec![label("battery "), Span::raw(battery)],
            vec![label("beacon "), Span::raw(beacon)],
        ],
    ));
    let flag = |bit: u8, name: &'static str| -> Vec<Span<'static>> {
        vec![if t.flags & bit != 0 {
            Span::styled(format!("■{name}"), Style::new().fg(Color::Yellow).bold())
        } else {
            Span::styled(format!("□{name}"), dim)
        }]
    };
    rows.push((
        1,
        vec![
            flag(flags::GROUND, "ground"),
            flag(flags::LINE, "line"),
            flag(flags::CONTACT, "contact"),
            flag(flags::FAILSAFE, "failsafe"),
            flag(flags::ARRIVED, "arrived"),
            vec![label("lines "), Span::raw(t.line_events.to_string())],
        ],
    ));
    rows.push((
        2,
        vec![vec![
            label("IR "),
            Span::raw(readings(&t.ir.values(), profile.ir.count)),
        ]],
    ));
    if has(caps::AMBIENT_LIGHT) {
        rows.push((
            2,
            vec![vec![
                label("light "),
                Span::raw(readings(&t.light.values(), 8)),
            ]],
        ));
    }
    if profile.id == ProfileId::Alice {
        rows.push((2, super::alice_sensors::text_row(app)));
    }
    fit(rows, width)
}

fn readings(v: &[u16; 8], n: usize) -> String {
    v.iter()
        .take(n)
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Names of the active behaviour bits (seed 000 §4).
pub fn behaviour_names(active: u8) -> String {
    let names = [
        (behaviours::AVOID, "avoid"),
        (behaviours::EDGE, "edge"),
        (behaviours::DRIFT, "drift"),
        (behaviours::TURN, "turn"),
        (behaviours::LIGHT, "light"),
        (behaviours::WALL_FOLLOW, "wall"),
        (behaviours::GUIDED, "guided"),
    ];
    let on: Vec<&str> = names
        .iter()
        .filter(|(b, _)| active & b != 0)
        .map(|(_, n)| *n)
        .collect();
    if on.is_empty() {
        "none".into()
    } else {
        on.join(" ")
    }
}
