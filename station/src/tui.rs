//! The interactive terminal: set up, run the event loop, and always restore the terminal.
//!
//! Layer: the TUI's I/O edge. Terminal events come from a reader thread (crossterm's blocking
//! `read`, as gitui does), link events from the link task; both become `Action`s for
//! `App::update`, the app's outbox goes to the link, and the screen is redrawn when something
//! changed (no redraw at all while nothing happens). The terminal is restored on quit, on
//! error and on panic (a hook installed before raw mode is entered). What can fail: terminal
//! I/O (`io::Error`).

use std::io::{self, stdout};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use ratatui::crossterm::event::{self, DisableMouseCapture, EnableMouseCapture, Event};
use ratatui::crossterm::execute;
use ratatui::DefaultTerminal;
use tokio::sync::mpsc;
use tokio::time::Instant;

use crate::action::Action;
use crate::app::App;
use crate::link::RunningLink;
use crate::{input, ui};

/// Time between ticks (teleop repetition needs 100 ms; ticks at twice that rate).
const TICK: Duration = Duration::from_millis(50);

/// Runs the TUI until the operator quits. Restores the terminal whatever happens.
pub async fn run(mut app: App, mut link: RunningLink) -> io::Result<()> {
    install_panic_hook();
    let mut terminal = ratatui::try_init()?;
    let result = async {
        execute!(stdout(), EnableMouseCapture)?;
        event_loop(&mut terminal, &mut app, &mut link).await
    }
    .await;
    restore();
    // Let the link send a final Stop and close the port.
    link.handle.shutdown();
    let _ = tokio::time::timeout(Duration::from_secs(1), &mut link.task).await;
    result
}

/// Leaves raw mode, the alternate screen and mouse capture. Safe to call twice.
pub fn restore() {
    let _ = execute!(stdout(), DisableMouseCapture);
    ratatui::restore();
}

fn install_panic_hook() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        restore();
        previous(info);
    }));
}

async fn event_loop(
    terminal: &mut DefaultTerminal,
    app: &mut App,
    link: &mut RunningLink,
) -> io::Result<()> {
    let size = terminal.size()?;
    app.update(Action::Resize {
        width: size.width,
        height: size.height,
    });
    let (input_tx, mut input_rx) = mpsc::unbounded_channel();
    let stop = Arc::new(AtomicBool::new(false));
    let reader = spawn_reader(input_tx, Arc::clone(&stop));
    let t0 = Instant::now();
    let mut tick = tokio::time::interval(TICK);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let mut dirty = true;
    let result = loop {
        if dirty {
            if let Err(e) = terminal.draw(|f| ui::render(app, f)) {
                break Err(e);
            }
            dirty = false;
        }
        tokio::select! {
            ev = input_rx.recv() => match ev {
                Some(Ok(ev)) => {
                    if let Some(a) = input::action_for(app, &ev) {
                        app.update(a);
                    }
                    dirty = true;
                }
                Some(Err(e)) => break Err(e),
                None => break Ok(()),
            },
            ev = link.events.recv() => {
                if let Some(ev) = ev {
                    app.update(Action::Link(ev));
                    dirty = true;
                }
            }
            _ = tick.tick() => {
                let driving = app.teleop.driving;
                app.update(Action::Tick { now_ms: t0.elapsed().as_millis() as u64 });
                dirty |= driving;
            }
        }
        for (id, command) in app.take_outbox() {
            link.handle.submit_with_id(id, command);
        }
        if app.quit {
            break Ok(());
        }
    };
    stop.store(true, Ordering::Relaxed);
    let _ = reader.join();
    result
}

/// Reads terminal events on a thread; polls so it notices `stop` within 100 ms.
fn spawn_reader(
    tx: mpsc::UnboundedSender<io::Result<Event>>,
    stop: Arc<AtomicBool>,
) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        while !stop.load(Ordering::Relaxed) {
            match event::poll(Duration::from_millis(100)) {
                Ok(true) => {
                    if tx.send(event::read()).is_err() {
                        return;
                    }
                }
                Ok(false) => {}
                Err(e) => {
                    let _ = tx.send(Err(e));
                    return;
                }
            }
        }
    })
}
