//! Transfers on screen: the upload prompt, the progress bar, and the robot's plan on the map.
//!
//! Layer: presentation. The prompt and the progress bar are drawn over the bottom of the main
//! area (as the link notice is), the prompt above the bar; they appear only while the prompt
//! is open or a transfer the operator started runs (the live map's downloads while exploring
//! draw no bar: they are a few hundred bytes a second). [`RobotPlanLayer`] draws the plan the
//! robot holds, as downloaded, beside the station's own plan layers. Cannot fail.

use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style, Stylize};
use ratatui::text::{Line, Span};
use ratatui::widgets::canvas::{Context, Line as CLine};
use ratatui::widgets::{Block, Clear, Gauge, Paragraph};
use ratatui::Frame;

use super::layer::{MapLayer, MapView};
use crate::app::App;

/// The robot's plan.
pub const ROBOT_PLAN: Color = Color::LightMagenta;
/// Layer name of the robot's plan.
pub const ROBOT_PLAN_LAYER: &str = "robot plan";
/// Most waypoints marked individually.
const MAX_MARKS: usize = 60;

/// Draws the prompt and the progress bar, if any, over the bottom of `main`.
pub fn render(app: &App, frame: &mut Frame, main: Rect) {
    let mut bottom = main.y + main.height;
    if let Some((p, what)) = app.transfers.shown_progress() {
        let area = band(main, bottom, 3);
        bottom = area.y;
        let ratio = if p.total > 0 {
            (f64::from(p.done) / f64::from(p.total)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let label = if p.total > 0 {
            format!("{} / {} bytes", p.done, p.total)
        } else {
            "asking the robot".into()
        };
        frame.render_widget(Clear, area);
        frame.render_widget(
            Gauge::default()
                .block(Block::bordered().title(format!(" {what} ")))
                .gauge_style(Style::new().fg(Color::Cyan).bg(Color::Black))
                .ratio(ratio)
                .label(label),
            area,
        );
    }
    if let Some(text) = &app.transfers.prompt {
        let area = band(main, bottom, 3);
        let room = usize::from(area.width.saturating_sub(4));
        // The end of a long path is the part being typed: show that.
        let chars: Vec<char> = text.chars().collect();
        let shown: String = chars
            .get(chars.len().saturating_sub(room.saturating_sub(1))..)
            .unwrap_or(&[])
            .iter()
            .collect();
        frame.render_widget(Clear, area);
        frame.render_widget(
            Paragraph::new(Line::from(vec![
                // A suggestion shows selected: the first key typed replaces it.
                if app.transfers.prompt_suggested {
                    Span::styled(shown, Style::new().add_modifier(Modifier::REVERSED))
                } else {
                    Span::raw(shown)
                },
                Span::styled("█", Style::new().fg(Color::Yellow)),
            ]))
            .block(
                Block::bordered()
                    .title(" Upload: an arena or map file, a map/plan object, a calibration ")
                    .title_bottom(
                        " Enter uploads · typing replaces, End edits · Ctrl-U clears · Esc ",
                    ),
            ),
            area,
        );
    }
}

/// A band `height` rows tall ending at row `bottom` of `main`, inset by a column each side.
fn band(main: Rect, bottom: u16, height: u16) -> Rect {
    let height = height.min(main.height);
    Rect {
        x: main.x + 1.min(main.width),
        y: bottom.saturating_sub(height).max(main.y),
        width: main.width.saturating_sub(2),
        height,
    }
}

/// The plan the robot holds, as downloaded (or uploaded).
pub struct RobotPlanLayer;

impl MapLayer for RobotPlanLayer {
    fn name(&self) -> &'static str {
        ROBOT_PLAN_LAYER
    }

    fn dots(&self, app: &App) -> bool {
        app.transfers.robot_plan.is_some()
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let Some((_, points)) = &app.transfers.robot_plan else {
            return;
        };
        for w in points.windows(2) {
            ctx.draw(&CLine {
                x1: w[0].0,
                y1: w[0].1,
                x2: w[1].0,
                y2: w[1].1,
                color: ROBOT_PLAN,
            });
        }
        if points.len() <= MAX_MARKS {
            for (x, y) in points {
                ctx.print(*x, *y, "◆".light_magenta());
            }
        }
    }
}
