//! The interactive terminal: set up, run the event loop, and always restore the terminal.
//!
//! Layer: the TUI's I/O edge. Terminal events come from a reader thread (crossterm's blocking
//! `read`, as gitui does), link events from the link task; both become `Action`s for
//! `App::update`, the app's outbox goes to the link, and the screen is redrawn when something
//! changed (no redraw at all while nothing happens): at once after a key, at most `LINK_FPS`
//! times a second for the link's changes, however fast telemetry comes. The link's tap goes to
//! the `TuiRecorder` (the `R` key), which writes it only while recording. The terminal is
//! restored on quit, on
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
use crate::record::live::TuiRecorder;
use crate::{input, ui};

/// Time between ticks (teleop repetition needs 100 ms; ticks at twice that rate).
const TICK: Duration = Duration::from_millis(50);
/// Most redraws a second for changes that come from the link or the clock; a key redraws at
/// once. 50 Hz telemetry and truth are 100 events a second: drawing each took the whole TUI to
/// ~5 % of a core; at this rate it is ~2 %, of which drawing ~0.6 % (README "Performance").
pub const LINK_FPS: u32 = 10;

/// Runs the TUI until the operator quits. Restores the terminal whatever happens. `recorder`
/// records the link while the operator asks (`R`); a recording running at quit is saved.
pub async fn run(mut app: App, mut link: RunningLink, mut recorder: TuiRecorder) -> io::Result<()> {
    install_panic_hook();
    let mut terminal = ratatui::try_init()?;
    let result = async {
        execute!(stdout(), EnableMouseCapture)?;
        event_loop(&mut terminal, &mut app, &mut link, &mut recorder).await
    }
    .await;
    restore();
    if let Some(note) = recorder.stop() {
        app.update(Action::Recording(note));
    }
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

/// Restores the terminal before a panic message is printed.
pub(crate) fn install_panic_hook() {
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
    recorder: &mut TuiRecorder,
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
    // A key's effect is drawn at once; the link's at most `LINK_FPS` times a second.
    let mut urgent = true;
    let frame = Duration::from_secs(1) / LINK_FPS;
    let mut last_draw = Instant::now();
    // One timer for the next allowed redraw, re-armed only when that time changes.
    let redraw = tokio::time::sleep_until(last_draw + frame);
    tokio::pin!(redraw);
    let result = loop {
        if dirty && (urgent || last_draw.elapsed() >= frame) {
            if let Err(e) = terminal.draw(|f| ui::render(app, f)) {
                break Err(e);
            }
            last_draw = Instant::now();
            dirty = false;
            urgent = false;
        }
        if dirty && redraw.deadline() != last_draw + frame {
            redraw.as_mut().reset(last_draw + frame);
        }
        tokio::select! {
            ev = input_rx.recv() => match ev {
                Some(Ok(ev)) => {
                    match input::action_for(app, &ev) {
                        // The loop owns the recording's file: it starts or stops it.
                        Some(Action::ToggleRecording) => {
                            app.update(Action::Recording(recorder.toggle()));
                        }
                        Some(a) => app.update(a),
                        None => {}
                    }
                    dirty = true;
                    urgent = true;
                }
                Some(Err(e)) => break Err(e),
                None => break Ok(()),
            },
            Some(ev) = link.events.recv() => {
                // Everything already queued in one go: one wake-up, one redraw decision.
                on_link(app, recorder, ev);
                while let Ok(ev) = link.events.try_recv() {
                    on_link(app, recorder, ev);
                }
                // The tap's records carry their own times: taking them here, with the
                // events that follow them, costs no wake-up of its own.
                if let Some(note) = recorder.drain_taps() {
                    app.update(Action::Recording(note));
                }
                dirty = true;
            }
            _ = tick.tick() => {
                let driving = app.teleop.driving;
                app.update(Action::Tick { now_ms: t0.elapsed().as_millis() as u64 });
                dirty |= driving;
                let note = recorder.drain_taps().or_else(|| recorder.tick());
                if let Some(note) = note {
                    app.update(Action::Recording(note));
                    dirty = true;
                }
            }
            () = &mut redraw, if dirty => {}
        }
        for (id, command) in app.take_outbox() {
            link.handle.submit_with_id(id, command);
        }
        for t in app.transfers.take_frames() {
            link.handle.transfer(t);
        }
        if app.quit {
            break Ok(());
        }
    };
    stop.store(true, Ordering::Relaxed);
    let _ = reader.join();
    result
}

/// One link event: to the recorder (connection changes), then to the app.
fn on_link(app: &mut App, recorder: &mut TuiRecorder, ev: crate::link::LinkEvent) {
    if let Some(note) = recorder.on_link_event(&ev) {
        app.update(Action::Recording(note));
    }
    app.update(Action::Link(ev));
}

/// Reads terminal events on a thread; polls so it notices `stop` within 100 ms.
pub(crate) fn spawn_reader(
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
