//! ALICE's sensors in the sensor panel (seed 001 §3.1): 24 whiskers and 24 photoresistors,
//! which telemetry does not carry: they come with each situation (message kind 16, three a
//! second), so the panel shows the last situation's.
//!
//! Layer: presentation. The glyph faces up like the other robots': a whisker is a short
//! spoke out from the body, red while it touches and dark grey otherwise; a photoresistor is a
//! tick on the outer ring, longer when brighter. The text row counts the touches, names the
//! brightest direction and says how old the situation is by its sequence number.

use protocol::ALICE_SENSORS;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::text::Span;
use ratatui::widgets::canvas::{Canvas, Line as CLine};
use ratatui::Frame;

use super::sensors::{draw_body, glyph_bounds, BODY, RING};
use crate::app::App;

/// Whisker length in glyph units (the body and ring radii are the other glyph's).
const WHISKER: f64 = 0.85;
const LIGHT_LEN: f64 = 0.9;

/// Direction of sensor `i` on screen, the robot facing up.
fn direction(i: usize) -> (f64, f64) {
    let a = std::f64::consts::FRAC_PI_2 + f64::from(robot_firmware::alice::sensor_angle_rad(i));
    (a.cos(), a.sin())
}

/// The glyph: body, heading, whiskers, photoresistor ring (empty until a situation came).
pub fn render_glyph(app: &App, frame: &mut Frame, area: Rect) {
    let (half_x, half_y) = glyph_bounds(area);
    let last = app.qt.last;
    let stale = app.stale_s().is_some();
    let tint = move |c: Color| if stale { Color::DarkGray } else { c };
    let canvas = Canvas::default()
        .marker(Marker::Braille)
        .x_bounds([-half_x, half_x])
        .y_bounds([-half_y, half_y])
        .paint(move |ctx| {
            draw_body(ctx);
            let Some(s) = last else { return };
            ctx.layer();
            for i in 0..ALICE_SENSORS {
                let (dx, dy) = direction(i);
                let touch = s.whiskers & (1 << i) != 0;
                ctx.draw(&CLine {
                    x1: dx * (BODY + 0.1),
                    y1: dy * (BODY + 0.1),
                    x2: dx * (BODY + 0.1 + WHISKER),
                    y2: dy * (BODY + 0.1 + WHISKER),
                    color: tint(if touch { Color::Red } else { Color::DarkGray }),
                });
                let bright = f64::from(s.light[i]) / 255.0;
                if bright > 0.0 {
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

/// The text row: touches, the brightest photoresistor, the situation's number.
pub fn text_row(app: &App) -> Vec<Vec<Span<'static>>> {
    let dim = Style::new().fg(Color::DarkGray);
    let Some(s) = app.qt.last else {
        return vec![vec![Span::styled("whiskers, light: no situation yet", dim)]];
    };
    let touching = s.whiskers.count_ones();
    let (brightest, value) = s
        .light
        .iter()
        .enumerate()
        .max_by_key(|&(i, &v)| (v, std::cmp::Reverse(i)))
        .map_or((0, 0), |(i, &v)| (i, v));
    vec![
        vec![
            Span::styled("whiskers ", dim),
            Span::raw(format!("{touching} of {ALICE_SENSORS}")),
        ],
        vec![
            Span::styled("light ", dim),
            Span::raw(format!("max {value} at {}°", brightest * 15)),
        ],
        vec![
            Span::styled("situation ", dim),
            Span::raw(format!("#{}", s.seq)),
        ],
    ]
}
