//! Terminal input to `Action`s: the key map and mouse clicks.
//!
//! Layer: the first step of the one-way flow. It reads the app (which mode the keys are in,
//! where the map is drawn) but changes nothing. Key bindings depend on the context, innermost
//! first: help open, typing a path in the upload prompt, typing a log filter, typing a
//! parameter value, typing a parameter search, the go-to cursor, the parameter view, the map's zoom and pan keys (while
//! the map is shown), then the global keys. Key release events (kitty protocol terminals) are
//! ignored.

use protocol::Mode;
use ratatui::crossterm::event::{
    Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers, MouseButton, MouseEventKind,
};
use ratatui::layout::Rect;

use crate::action::Action;
use crate::app::transfers::TransferAction;
use crate::app::{App, View, MODES, V_STEP, W_STEP, ZOOM_STEP};
use crate::ui::{self, localization, map_layers, Panel};

/// Cursor step of one arrow press in go-to mode, metres (shift: 5x).
pub const CURSOR_STEP_M: f64 = 0.1;

/// The action for one terminal event, if any.
pub fn action_for(app: &App, ev: &Event) -> Option<Action> {
    match ev {
        Event::Resize(w, h) => Some(Action::Resize {
            width: *w,
            height: *h,
        }),
        Event::Key(k) if k.kind != KeyEventKind::Release => key(app, k),
        // Under the help nothing is clicked: the wheel scrolls it.
        Event::Mouse(m) if app.help => match m.kind {
            MouseEventKind::ScrollUp => help_scroll(app, -3),
            MouseEventKind::ScrollDown => help_scroll(app, 3),
            _ => None,
        },
        Event::Mouse(m) => {
            let screen = Rect::new(0, 0, app.size.0, app.size.1);
            let areas = ui::areas(screen, app);
            match m.kind {
                MouseEventKind::Down(MouseButton::Left) => {
                    let map = areas.find(Panel::Map)?;
                    let inner = inner_of(ui::map::map_area(app, map));
                    let (x_m, y_m) = ui::map::to_world(app, inner, m.column, m.row)?;
                    // A click only places the cursor unless the operator asked for clicks
                    // that send (`--click-goes`): one stray click must not drive the robot.
                    Some(if app.click_goes {
                        Action::GoToPoint { x_m, y_m }
                    } else {
                        Action::CursorAt { x_m, y_m }
                    })
                }
                MouseEventKind::ScrollUp | MouseEventKind::ScrollDown => {
                    let up = matches!(m.kind, MouseEventKind::ScrollUp);
                    // Over the map the wheel zooms about the pointer; elsewhere it scrolls
                    // the log.
                    let on_map = areas
                        .find(Panel::Map)
                        .map(|r| inner_of(ui::map::map_area(app, r)))
                        .and_then(|inner| wheel_point(inner, m.column, m.row));
                    Some(match on_map {
                        Some(at) => Action::MapZoom {
                            factor: if up { ZOOM_STEP } else { 1.0 / ZOOM_STEP },
                            at,
                        },
                        None => Action::LogScroll(if up { 3 } else { -3 }),
                    })
                }
                _ => None,
            }
        }
        _ => None,
    }
}

/// The help scrolled by `d` lines, within what it holds on this screen.
fn help_scroll(app: &App, d: i32) -> Option<Action> {
    let screen = Rect::new(0, 0, app.size.0, app.size.1);
    let max = i32::from(ui::help::max_scroll(screen, app.in_fleet()));
    let to = (i32::from(app.help_scroll) + d).clamp(0, max);
    Some(Action::HelpScroll(u16::try_from(to).unwrap_or(0)))
}

/// Where `col`, `row` is in `inner`, as fractions of its span from its centre (x right, y
/// up), if inside.
fn wheel_point(inner: Rect, col: u16, row: u16) -> Option<(f64, f64)> {
    let inside = col >= inner.x
        && col < inner.x + inner.width
        && row >= inner.y
        && row < inner.y + inner.height;
    inside.then(|| {
        (
            (f64::from(col - inner.x) + 0.5) / f64::from(inner.width) - 0.5,
            0.5 - (f64::from(row - inner.y) + 0.5) / f64::from(inner.height),
        )
    })
}

/// The area inside a panel's border.
fn inner_of(r: Rect) -> Rect {
    ratatui::widgets::Block::bordered().inner(r)
}

fn key(app: &App, k: &KeyEvent) -> Option<Action> {
    let ctrl = k.modifiers.contains(KeyModifiers::CONTROL);
    if ctrl && matches!(k.code, KeyCode::Char('c')) {
        return Some(Action::Quit);
    }
    if app.help {
        // Every key stops here: one that closed the help and then drove (an arrow after
        // PgUp) would move the robot from a screen that showed no robot.
        let screen = Rect::new(0, 0, app.size.0, app.size.1);
        let page = i32::from(ui::help::page(screen, app.in_fleet()));
        return match k.code {
            KeyCode::Esc | KeyCode::Char('?' | 'q') => Some(Action::ToggleHelp),
            KeyCode::Up | KeyCode::Char('k') => help_scroll(app, -1),
            KeyCode::Down | KeyCode::Char('j') => help_scroll(app, 1),
            KeyCode::PageUp => help_scroll(app, -page),
            KeyCode::PageDown | KeyCode::Char(' ') => help_scroll(app, page),
            KeyCode::Home => help_scroll(app, -i32::from(u16::MAX)),
            KeyCode::End => help_scroll(app, i32::from(u16::MAX)),
            _ => None,
        };
    }
    if app.transfers.prompt.is_some() {
        return match k.code {
            KeyCode::Char('u') if ctrl => Some(Action::Transfer(TransferAction::PromptClear)),
            KeyCode::Char(_) if ctrl => None,
            KeyCode::End | KeyCode::Left | KeyCode::Right => {
                Some(Action::Transfer(TransferAction::PromptKeep))
            }
            KeyCode::Char(c) => Some(Action::Transfer(TransferAction::PromptInput(c))),
            KeyCode::Backspace => Some(Action::Transfer(TransferAction::PromptBackspace)),
            KeyCode::Enter => Some(Action::Transfer(TransferAction::PromptCommit)),
            KeyCode::Esc => Some(Action::Transfer(TransferAction::PromptCancel)),
            _ => None,
        };
    }
    if app.log.filter_input.is_some() {
        return match k.code {
            KeyCode::Char(_) if ctrl => None,
            KeyCode::Char(c) => Some(Action::LogFilterInput(c)),
            KeyCode::Backspace => Some(Action::LogFilterBackspace),
            KeyCode::Enter => Some(Action::LogFilterCommit),
            KeyCode::Esc => Some(Action::Back),
            _ => None,
        };
    }
    if app.params.input.is_some() {
        return match k.code {
            KeyCode::Char(c) if c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E') => {
                Some(Action::ParamInput(c))
            }
            KeyCode::Backspace => Some(Action::ParamBackspace),
            KeyCode::Enter => Some(Action::ParamCommit),
            KeyCode::Esc => Some(Action::Back),
            _ => None,
        };
    }
    if app.params.searching {
        return match k.code {
            KeyCode::Char(_) if ctrl => None,
            KeyCode::Char(c) => Some(Action::ParamSearchInput(c)),
            KeyCode::Backspace => Some(Action::ParamSearchBackspace),
            KeyCode::Up => Some(Action::ParamSelect(-1)),
            KeyCode::Down => Some(Action::ParamSelect(1)),
            KeyCode::Enter => Some(Action::ParamSearchDone),
            KeyCode::Esc => Some(Action::Back),
            _ => None,
        };
    }
    if app.map.cursor_mode {
        let step = if k.modifiers.contains(KeyModifiers::SHIFT) {
            5.0 * CURSOR_STEP_M
        } else {
            CURSOR_STEP_M
        };
        let mv = |dx: f64, dy: f64| Some(Action::MoveCursor { dx, dy });
        match k.code {
            KeyCode::Up | KeyCode::Char('k') | KeyCode::Char('K') => return mv(0.0, step),
            KeyCode::Down | KeyCode::Char('j') | KeyCode::Char('J') => return mv(0.0, -step),
            KeyCode::Left | KeyCode::Char('h') | KeyCode::Char('H') => return mv(-step, 0.0),
            KeyCode::Right | KeyCode::Char('l') | KeyCode::Char('L') => return mv(step, 0.0),
            KeyCode::Enter => return Some(Action::GoToCursor),
            KeyCode::Esc => return Some(Action::Back),
            _ => {}
        }
    }
    if app.view == View::Params {
        match k.code {
            KeyCode::Up | KeyCode::Char('k') => return Some(Action::ParamSelect(-1)),
            KeyCode::Down | KeyCode::Char('j') => return Some(Action::ParamSelect(1)),
            KeyCode::PageUp => return Some(Action::ParamSelect(-10)),
            KeyCode::PageDown => return Some(Action::ParamSelect(10)),
            KeyCode::Char('r') => return Some(Action::ParamRead),
            KeyCode::Char('R') => return Some(Action::ParamReadAll),
            KeyCode::Enter | KeyCode::Char('e') => return Some(Action::ParamEdit),
            KeyCode::Char('/') => return Some(Action::ParamSearchStart),
            // No driving from the table: arrows select there, so WASD would surprise.
            KeyCode::Char('w' | 'a' | 's' | 'd') | KeyCode::Left | KeyCode::Right => return None,
            _ => {}
        }
    }
    if matches!(app.view, View::Dashboard | View::Map) {
        let pan = |dx: i8, dy: i8| Some(Action::MapPan { dx, dy });
        let zoom = |factor: f64| {
            Some(Action::MapZoom {
                factor,
                at: (0.0, 0.0),
            })
        };
        match k.code {
            KeyCode::Char('h') => return pan(-1, 0),
            KeyCode::Char('l') => return pan(1, 0),
            KeyCode::Char('k') => return pan(0, 1),
            KeyCode::Char('j') => return pan(0, -1),
            KeyCode::Char('z') => return zoom(ZOOM_STEP),
            KeyCode::Char('Z') => return zoom(1.0 / ZOOM_STEP),
            KeyCode::Char('F') => {
                let screen = Rect::new(0, 0, app.size.0, app.size.1);
                let keep = ui::areas(screen, app)
                    .find(Panel::Map)
                    .map(|r| inner_of(ui::map::map_area(app, r)))
                    .map_or(app.map.pan(), |inner| ui::map::pan_of_view(app, inner));
                return Some(Action::MapFollow { keep });
            }
            _ => {}
        }
    }
    global(k)
}

fn global(k: &KeyEvent) -> Option<Action> {
    let drive = |dv: i16, dw: i16| Some(Action::Drive { dv, dw });
    match k.code {
        KeyCode::Char('q') => Some(Action::Quit),
        KeyCode::Char('?') => Some(Action::ToggleHelp),
        KeyCode::Esc => Some(Action::Back),
        KeyCode::Tab => Some(Action::NextView),
        KeyCode::BackTab => Some(Action::PrevView),
        KeyCode::F(n) => View::ALL
            .get(usize::from(n).checked_sub(1)?)
            .map(|v| Action::ShowView(*v)),
        KeyCode::Up | KeyCode::Char('w') => drive(V_STEP, 0),
        KeyCode::Down | KeyCode::Char('s') => drive(-V_STEP, 0),
        KeyCode::Left | KeyCode::Char('a') => drive(0, W_STEP),
        KeyCode::Right | KeyCode::Char('d') => drive(0, -W_STEP),
        KeyCode::Char(' ') => Some(Action::StopDriving),
        KeyCode::Char(c @ '0'..='9') => {
            let i = c.to_digit(10)? as usize;
            MODES.get(i).map(|m: &Mode| Action::SetMode(*m))
        }
        KeyCode::Char('g') => Some(Action::GoToCursorStart),
        KeyCode::Char('p') => Some(Action::ShowView(View::Params)),
        KeyCode::Char('+') | KeyCode::Char('=') => Some(Action::RateStep(1)),
        KeyCode::Char('-') => Some(Action::RateStep(-1)),
        KeyCode::Char('c') => Some(Action::ChartNext),
        KeyCode::Char('t') => Some(Action::ToggleLayer("truth")),
        KeyCode::Char('x') => Some(Action::ClearTracks),
        KeyCode::Char('P') => Some(Action::PlanLocal),
        KeyCode::Char('G') => Some(Action::PlanTargetReset),
        KeyCode::Char('R') => Some(Action::ToggleRecording),
        KeyCode::Char('u') => Some(Action::Transfer(TransferAction::OpenPrompt)),
        KeyCode::Char('M') => Some(Action::Transfer(TransferAction::DownloadMap)),
        KeyCode::Char('O') => Some(Action::Transfer(TransferAction::PlanOnRobot)),
        KeyCode::Char('X') => Some(Action::Transfer(TransferAction::ExecutePlan)),
        KeyCode::Char('E') => Some(Action::Transfer(TransferAction::StartExploration)),
        KeyCode::Char('o') => Some(Action::ToggleLayer(map_layers::GRID)),
        KeyCode::Char('r') => Some(Action::ToggleLayer(map_layers::REGIONS)),
        KeyCode::Char('n') => Some(Action::ToggleLayer(map_layers::PLAN)),
        KeyCode::Char('m') => Some(Action::ToggleLayer(map_layers::SMOOTHED)),
        KeyCode::Char('e') => Some(Action::ToggleLayer(map_layers::ENDS)),
        KeyCode::Char('y') => Some(Action::ToggleLayer(localization::ODOMETRY)),
        KeyCode::Char('i') => Some(Action::ToggleLayer(localization::LINES)),
        KeyCode::Char('v') => Some(Action::ToggleLayer(localization::PPD)),
        KeyCode::Char('f') => Some(Action::ToggleLayer(localization::FLOOR)),
        KeyCode::Char('T') => Some(Action::ToggleLayer(crate::ui::qt_map::QT)),
        KeyCode::Char('S') => Some(Action::SetMode(Mode::Survey)),
        KeyCode::PageUp => Some(Action::LogScroll(5)),
        KeyCode::PageDown => Some(Action::LogScroll(-5)),
        KeyCode::End => Some(Action::LogFollow),
        KeyCode::Home => Some(Action::LogTop),
        KeyCode::Char('L') => Some(Action::LogLevelCycle),
        KeyCode::Char('/') => Some(Action::LogFilterStart),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::AppOptions;
    use ratatui::crossterm::event::MouseEvent;

    fn wheel(app: &App, up: bool, column: u16, row: u16) -> Option<Action> {
        action_for(
            app,
            &Event::Mouse(MouseEvent {
                kind: if up {
                    MouseEventKind::ScrollUp
                } else {
                    MouseEventKind::ScrollDown
                },
                column,
                row,
                modifiers: KeyModifiers::NONE,
            }),
        )
    }

    #[test]
    fn the_wheel_zooms_the_map_about_the_pointer_and_scrolls_the_log_elsewhere() {
        let mut app = App::new(AppOptions::default());
        app.update(Action::Resize {
            width: 150,
            height: 40,
        });
        let screen = Rect::new(0, 0, 150, 40);
        let areas = ui::areas(screen, &app);
        let map = inner_of(ui::map::map_area(&app, areas.find(Panel::Map).unwrap()));
        let centre = (map.x + map.width / 2, map.y + map.height / 2);
        match wheel(&app, true, centre.0, centre.1) {
            Some(Action::MapZoom { factor, at }) => {
                assert_eq!(factor, ZOOM_STEP);
                assert!(at.0.abs() < 0.05 && at.1.abs() < 0.05, "{at:?}");
            }
            other => panic!("{other:?}"),
        }
        // The top-left corner of the map is left and up of its centre.
        match wheel(&app, false, map.x, map.y) {
            Some(Action::MapZoom { factor, at }) => {
                assert!(factor < 1.0);
                assert!(at.0 < -0.4 && at.1 > 0.4, "{at:?}");
            }
            other => panic!("{other:?}"),
        }
        let log = areas.find(Panel::Log).unwrap();
        assert_eq!(
            wheel(&app, true, log.x + 2, log.y + 2),
            Some(Action::LogScroll(3))
        );
    }

    fn key_event(code: KeyCode) -> Event {
        Event::Key(KeyEvent::new(code, KeyModifiers::NONE))
    }

    #[test]
    fn no_key_or_click_in_the_help_reaches_the_robot() {
        let mut app = App::new(AppOptions::default());
        app.update(Action::ToggleHelp);
        let robot = |a: &Option<Action>| {
            matches!(
                a,
                Some(
                    Action::Drive { .. }
                        | Action::StopDriving
                        | Action::SetMode(_)
                        | Action::GoToCursorStart
                        | Action::GoToCursor
                        | Action::GoToPoint { .. }
                        | Action::CursorAt { .. }
                        | Action::Transfer(_)
                        | Action::ToggleRecording
                        | Action::Quit
                )
            )
        };
        let mut codes = vec![
            KeyCode::Up,
            KeyCode::Down,
            KeyCode::Left,
            KeyCode::Right,
            KeyCode::PageUp,
            KeyCode::PageDown,
            KeyCode::Home,
            KeyCode::End,
            KeyCode::Enter,
            KeyCode::Tab,
            KeyCode::F(4),
        ];
        codes.extend("wasd 0123456789gREXOM".chars().map(KeyCode::Char));
        for code in codes {
            let a = action_for(&app, &key_event(code));
            assert!(!robot(&a), "{code:?} in the help gave {a:?}");
            assert_ne!(a, Some(Action::ToggleHelp), "{code:?} closed the help");
        }
        // PgUp then an arrow: the help is still open and the arrow scrolls it.
        app.update(Action::HelpScroll(3));
        let page_up = action_for(&app, &key_event(KeyCode::PageUp));
        assert_eq!(page_up, Some(Action::HelpScroll(0)));
        for close in [KeyCode::Esc, KeyCode::Char('?'), KeyCode::Char('q')] {
            assert_eq!(
                action_for(&app, &key_event(close)),
                Some(Action::ToggleHelp)
            );
        }
        let click = Event::Mouse(MouseEvent {
            kind: MouseEventKind::Down(MouseButton::Left),
            column: 40,
            row: 10,
            modifiers: KeyModifiers::NONE,
        });
        assert_eq!(action_for(&app, &click), None);
    }

    #[test]
    fn a_click_on_the_map_places_the_cursor_unless_clicks_go() {
        for goes in [false, true] {
            let mut app = App::new(AppOptions {
                click_goes: goes,
                ..AppOptions::default()
            });
            app.update(Action::Resize {
                width: 80,
                height: 24,
            });
            let screen = Rect::new(0, 0, 80, 24);
            let map = ui::areas(screen, &app).find(Panel::Map).unwrap();
            let inner = inner_of(ui::map::map_area(&app, map));
            let click = Event::Mouse(MouseEvent {
                kind: MouseEventKind::Down(MouseButton::Left),
                column: inner.x + inner.width / 2,
                row: inner.y + inner.height / 2,
                modifiers: KeyModifiers::NONE,
            });
            let a = action_for(&app, &click);
            if goes {
                assert!(matches!(a, Some(Action::GoToPoint { .. })), "{a:?}");
            } else {
                assert!(matches!(a, Some(Action::CursorAt { .. })), "{a:?}");
            }
        }
    }

    #[test]
    fn while_a_log_filter_is_typed_letters_are_text_not_commands() {
        let mut app = App::new(AppOptions::default());
        app.update(Action::LogFilterStart);
        let key = |c| Event::Key(KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE));
        assert_eq!(
            action_for(&app, &key('q')),
            Some(Action::LogFilterInput('q'))
        );
        assert_eq!(
            action_for(&app, &key('E')),
            Some(Action::LogFilterInput('E'))
        );
    }
}
