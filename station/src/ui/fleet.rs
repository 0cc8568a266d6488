//! The fleet on screen: the fleet panel (one line per robot) and the other robots on the map.
//!
//! Layer: presentation, from the selected robot's `app.fleet` overlay (`app::fleet`); nothing
//! is drawn for a single robot. Each robot has a colour and a glyph, its number, so the map
//! reads without colour too; the selected robot is drawn by the map's own believed-pose layer
//! in its fleet colour, its number reversed.

use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style, Stylize};
use ratatui::text::{Line, Span};
use ratatui::widgets::canvas::{Context, Points};
use ratatui::widgets::{Block, Paragraph};
use ratatui::Frame;

use super::layer::{MapLayer, MapView};
use crate::app::App;

/// The robots' colours, by index: none is a colour the map uses for something else (magenta
/// truth, yellow go-to and beacon, light red plan target).
const COLOURS: [Color; 9] = [
    Color::Cyan,
    Color::LightGreen,
    Color::LightBlue,
    Color::White,
    Color::Green,
    Color::Blue,
    Color::LightCyan,
    Color::Gray,
    Color::Red,
];

/// Robot `i`'s colour.
pub fn colour(i: usize) -> Color {
    COLOURS[i % COLOURS.len()]
}

/// Robot `i`'s glyph on the map: its number in the fleet, as the picker's keys count.
pub fn glyph(i: usize) -> char {
    char::from_digit((i % 9) as u32 + 1, 10).unwrap_or('?')
}

/// The fleet panel: label, profile, mode and activity, link health, battery, stale marker.
pub fn render(app: &App, frame: &mut Frame, area: Rect) {
    let Some(f) = &app.fleet else { return };
    let label_w = f
        .robots
        .iter()
        .map(|r| r.label.chars().count())
        .max()
        .unwrap_or(0);
    let lines: Vec<Line> = f
        .robots
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let selected = i == f.selected;
            let mark = if selected { "▶" } else { " " };
            let mut glyph_style = Style::new().fg(colour(i)).add_modifier(Modifier::BOLD);
            if selected {
                glyph_style = glyph_style.add_modifier(Modifier::REVERSED);
            }
            let mut spans = vec![
                Span::raw(mark),
                Span::styled(glyph(i).to_string(), glyph_style),
                Span::raw(" "),
                Span::styled(
                    format!("{:<label_w$}", r.label),
                    if selected {
                        Style::new().bold()
                    } else {
                        Style::new()
                    },
                ),
                Span::raw("  "),
                Span::raw(format!("{:<16}  ", r.activity)),
            ];
            spans.push(Span::raw(match r.battery_v {
                Some(v) => format!("{v:.2} V  "),
                None => "        ".into(),
            }));
            if r.duplicate_id {
                spans.push(Span::styled(
                    "SAME ID  ",
                    Style::new().fg(Color::Red).bold(),
                ));
            }
            if let Some(s) = r.stale_s {
                spans.push(Span::styled(
                    format!("stale {s} s  "),
                    Style::new().dark_gray(),
                ));
            }
            // Last: why a link is down can be long, and a narrow panel cuts only that.
            spans.push(Span::styled(
                format!("link {}", crate::terminal_text::printable_text(&r.link)),
                if r.connected {
                    Style::new().fg(Color::Green)
                } else {
                    Style::new().fg(Color::Red)
                },
            ));
            Line::from(spans)
        })
        .collect();
    let n = f.robots.len();
    // A replay sends nothing: no "stop all" there.
    let title = if app.replaying {
        format!(
            " Fleet: {} of {n} — Tab/Alt-1..{n}/click picks ",
            f.selected + 1
        )
    } else {
        format!(
            " Fleet: {} of {n} — Tab/Alt-1..{n}/click picks, {} stops all ",
            f.selected + 1,
            crate::app::fleet::STOP_ALL_KEY
        )
    };
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title(title)),
        area,
    );
}

/// The other robots, each in its colour with its track and its number.
pub struct FleetLayer;

impl MapLayer for FleetLayer {
    fn name(&self) -> &'static str {
        "fleet"
    }

    fn dots(&self, app: &App) -> bool {
        app.in_fleet()
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let Some(f) = app.fleet.as_ref().filter(|_| app.in_fleet()) else {
            return;
        };
        for (i, r) in f.robots.iter().enumerate() {
            if i == f.selected {
                continue;
            }
            ctx.draw(&Points {
                coords: &r.track,
                color: colour(i),
            });
        }
        for (i, r) in f.robots.iter().enumerate() {
            if i == f.selected {
                continue;
            }
            if let Some((x, y, _)) = r.pose {
                ctx.print(x, y, glyph(i).to_string().fg(colour(i)).bold());
            }
        }
    }
}

/// The selected robot's colour and glyph in a fleet (the believed-pose layer uses them).
pub fn selected_mark(app: &App) -> Option<(Color, Span<'static>)> {
    let f = app.fleet.as_ref().filter(|_| app.in_fleet())?;
    let c = colour(f.selected);
    Some((
        c,
        glyph(f.selected)
            .to_string()
            .fg(c)
            .add_modifier(Modifier::BOLD | Modifier::REVERSED),
    ))
}
