//! Drawing: `render(&App, &mut Frame)` and the layout it uses.
//!
//! Layer: pure presentation (gitui's `draw(&self)`): reads the app immutably, writes cells, does
//! no I/O and changes nothing. The layout is a function of the terminal size and the view, so
//! input handling can find where the map was drawn (for mouse clicks) by calling `areas` with
//! the same arguments. Every panel degrades to something readable at 80 x 24 and uses the
//! room of a large terminal. Cannot fail: a panel too small for its content clips it.

pub mod alice_sensors;
pub mod charts;
pub mod fleet;
pub mod forage;
pub mod header;
pub mod help;
pub mod layer;
pub mod link;
pub mod localization;
pub mod log;
pub mod map;
pub mod map_layers;
pub mod params;
pub mod plan_panel;
pub mod qt_map;
pub mod retrace_layer;
pub mod sensors;
pub mod transfer;

use ratatui::layout::Rect;
use ratatui::Frame;

use crate::app::App;

pub use crate::app::layout::{areas, Areas, Panel};

/// Draws the whole screen.
pub fn render(app: &App, frame: &mut Frame) {
    let a = areas(frame.area(), app);
    header::render_header(app, frame, a.header);
    header::render_footer(app, frame, a.footer);
    for (panel, area) in &a.panels {
        match panel {
            Panel::Sensors => sensors::render(app, frame, *area),
            Panel::Charts => charts::render(app, frame, *area),
            Panel::Map => map::render(app, frame, *area),
            Panel::Link => link::render(app, frame, *area),
            Panel::Log => log::render(app, frame, *area),
            Panel::Params => params::render(app, frame, *area),
            Panel::Fleet => fleet::render(app, frame, *area),
        }
    }
    if let Some(main) = main_area(&a) {
        notice(app, frame, main);
        transfer::render(app, frame, main);
    }
    if app.help {
        help::render_keys(frame, frame.area(), app.in_fleet(), app.help_scroll);
    }
}

fn main_area(a: &Areas) -> Option<Rect> {
    a.panels
        .iter()
        .map(|(_, r)| *r)
        .reduce(|acc, r| acc.union(r))
}

/// When the link is down, says why in full over the bottom of the main area: a port held by
/// another program or a schema mismatch must be readable, not cut off in the header.
fn notice(app: &App, frame: &mut Frame, main: Rect) {
    use ratatui::style::{Color, Style};
    use ratatui::widgets::{Block, Clear, Paragraph, Wrap};
    // In a fleet the robot's fleet line and link panel say why, and the box would cover the
    // log where "stop all" reports each robot.
    if app.in_fleet() {
        return;
    }
    let (title, text) = match &app.connection {
        // A replay between sessions: the header says so; nobody is trying anything.
        crate::link::Connection::Closed { .. } if app.replaying => return,
        crate::link::Connection::Closed { reason } => (" Not connected ", reason.clone()),
        crate::link::Connection::Refused { message } => (" Robot refused ", message.clone()),
        _ => return,
    };
    let width = main.width.saturating_sub(4).max(10);
    let text = if app.replaying {
        format!("{text} (recorded).")
    } else {
        format!("{text}. The station keeps trying.")
    };
    let lines = (text.chars().count() as u16).div_ceil(width.saturating_sub(2).max(1));
    let height = (lines + 2).min(main.height);
    let area = Rect {
        x: main.x + (main.width - width.min(main.width)) / 2,
        y: main.y + main.height.saturating_sub(height + 1),
        width: width.min(main.width),
        height,
    };
    frame.render_widget(Clear, area);
    frame.render_widget(
        Paragraph::new(text)
            .wrap(Wrap { trim: true })
            .style(Style::new().fg(Color::Red))
            .block(Block::bordered().title(title)),
        area,
    );
}
