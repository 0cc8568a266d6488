//! The interactive terminal: set up, run the event loop, and always restore the terminal.
//!
//! Layer: the TUI's I/O edge. Terminal events come from crossterm's event stream (its thread
//! sleeps until an event: no polling), link events from the link task; both become `Action`s
//! for `App::update`, the app's outbox goes to the link, and the screen is redrawn when
//! something changed (no redraw at all while nothing happens): at once after a key, at most
//! once per `LINK_FRAME` (about `LINK_FPS` a second) for the link's changes, however fast
//! telemetry comes. Every timer
//! is on the `pace` grid, so the tick, the redraw limit and the paced link share wake-ups. The
//! viewport is fixed and resized on the terminal's resize events (a full-screen viewport asks
//! the terminal for its size before every frame, opening `/dev/tty` each time). The link's tap
//! goes to the `TuiRecorder` (the `R` key), which writes it only while recording, with the
//! lines each robot's app logs meanwhile (`App::take_station_lines`). The terminal
//! is restored on quit, on error, on panic (a hook installed before raw mode is entered) and on
//! SIGTERM, SIGHUP and SIGINT, which end the TUI as `q` does. What can fail: terminal I/O
//! (`io::Error`).

use std::io::{self, stdout};
use std::pin::Pin;
use std::time::Duration;

use futures_core::Stream;
use ratatui::crossterm::event::{DisableMouseCapture, EnableMouseCapture, Event, EventStream};
use ratatui::crossterm::execute;
use ratatui::crossterm::terminal::EnterAlternateScreen;
use ratatui::layout::Rect;
use ratatui::{DefaultTerminal, TerminalOptions, Viewport};
use tokio::signal::unix::{signal, Signal, SignalKind};
use tokio::sync::mpsc;
use tokio::time::Instant;

use crate::action::Action;
use crate::app::App;
use crate::awaited_replies::AwaitedReplies;
use crate::fleet::{self, Fleet, Member};
use crate::link::RunningLink;
use crate::record::live::TuiRecorder;
use crate::{pace, ui};

/// Time between ticks while driving: one `pace` slot (32 ms), so that teleop repeats every
/// three ticks, about every 100 ms (`app::TELEOP_PERIOD_MS`).
const DRIVING_TICK: Duration = pace::SLOT;
/// Time between ticks otherwise: nothing but transfers and recording notes needs them.
const IDLE_TICK: Duration = pace::SLOT.saturating_mul(2);
/// About the most redraws a second for changes that come from the link or the clock; a key
/// redraws at once. 50 Hz telemetry and truth are 100 events a second: drawing each took the
/// whole TUI to ~5 % of a core (docs/performance.md, the TUI CPU rows).
pub const LINK_FPS: u32 = 10;
/// The time between two redraws for the link's changes: `LINK_FPS` on whole slots (96 ms).
pub const LINK_FRAME: Duration = pace::SLOT.saturating_mul(3);

/// Runs the TUI until the operator quits. Restores the terminal whatever happens. `recorder`
/// records the link while the operator asks (`R`); a recording running at quit is saved.
pub async fn run(app: App, link: RunningLink, recorder: TuiRecorder) -> io::Result<()> {
    run_fleet(
        Fleet::new(vec![Member {
            port: app.port_label.clone(),
            app,
        }]),
        vec![link],
        recorder,
    )
    .await
}

/// `run` for several robots: `links[i]` is robot `i`'s link (`fleet`: one link task per
/// port; one robot's link going down leaves the others' alone). `recorder` records every
/// link's tap (`R`), all into one file.
pub async fn run_fleet(
    mut fleet: Fleet,
    mut links: Vec<RunningLink>,
    mut recorder: TuiRecorder,
) -> io::Result<()> {
    // Before raw mode: from here on, these signals end the loop instead of the process.
    let mut signals = StopSignals::new()?;
    install_panic_hook();
    let mut terminal = init_terminal()?;
    let result = async {
        execute!(stdout(), EnableMouseCapture)?;
        event_loop(
            &mut terminal,
            &mut fleet,
            &mut links,
            &mut recorder,
            &mut signals,
        )
        .await
    }
    .await;
    restore();
    if let Some(name) = signals.received {
        eprintln!("station: stopped by {name}");
    }
    if let Some(note) = recorder.stop() {
        fleet.update(Action::Recording(note));
    }
    // What the end of the recording asks the robots (hal_trace put back) goes before the
    // links close; a request submitted before the shutdown is written before it.
    for (m, link) in fleet.members.iter_mut().zip(links.iter()) {
        for (id, command, when) in m.app.take_outbox_timed() {
            link.handle.submit_when(id, command, when);
        }
    }
    // Let every link send a final Stop and close its port.
    for link in &links {
        link.handle.shutdown();
    }
    let _ = tokio::time::timeout(Duration::from_secs(1), async {
        for link in &mut links {
            let _ = (&mut link.task).await;
        }
    })
    .await;
    result
}

/// Leaves raw mode, the alternate screen and mouse capture. Safe to call twice.
pub fn restore() {
    let _ = execute!(stdout(), DisableMouseCapture);
    ratatui::restore();
}

/// Enters raw mode and the alternate screen with a viewport of the terminal's size now; the
/// loops resize it on `Event::Resize` (`resize`). Restores the terminal if that fails.
pub(crate) fn init_terminal() -> io::Result<DefaultTerminal> {
    let init = || {
        let (w, h) = ratatui::crossterm::terminal::size()?;
        let terminal = ratatui::try_init_with_options(TerminalOptions {
            viewport: Viewport::Fixed(Rect::new(0, 0, w, h)),
        })?;
        execute!(stdout(), EnterAlternateScreen)?;
        Ok(terminal)
    };
    init().inspect_err(|_| restore())
}

/// Follows a terminal resize (the viewport is fixed: nothing else notices).
pub(crate) fn resize(terminal: &mut DefaultTerminal, ev: &Event) -> io::Result<()> {
    if let Event::Resize(w, h) = *ev {
        terminal.resize(Rect::new(0, 0, w, h))?;
    }
    Ok(())
}

/// The signals that end the TUI cleanly (terminal restored, recording saved) rather than
/// killing it with the terminal left in raw mode on the alternate screen.
pub(crate) struct StopSignals {
    term: Signal,
    hup: Signal,
    int: Signal,
    /// The signal that ended the loop, if one did.
    pub received: Option<&'static str>,
}

impl StopSignals {
    /// Takes the signals over from their default action. Needs a tokio runtime.
    pub(crate) fn new() -> io::Result<StopSignals> {
        Ok(StopSignals {
            term: signal(SignalKind::terminate())?,
            hup: signal(SignalKind::hangup())?,
            int: signal(SignalKind::interrupt())?,
            received: None,
        })
    }

    /// Waits for one of them; remembers which.
    pub(crate) async fn recv(&mut self) {
        let name = tokio::select! {
            _ = self.term.recv() => "SIGTERM",
            _ = self.hup.recv() => "SIGHUP",
            _ = self.int.recv() => "SIGINT",
        };
        self.received = Some(name);
    }
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
    fleet: &mut Fleet,
    links: &mut [RunningLink],
    recorder: &mut TuiRecorder,
    signals: &mut StopSignals,
) -> io::Result<()> {
    let size = terminal.size()?;
    fleet.update(Action::Resize {
        width: size.width,
        height: size.height,
    });
    let (input_tx, mut input_rx) = mpsc::unbounded_channel();
    let reader = spawn_reader(input_tx);
    let t0 = Instant::now();
    // Every periodic timer is on the `pace` grid: they share wake-ups with each other and
    // with the paced link.
    let tick = tokio::time::sleep_until(pace::next_slot());
    tokio::pin!(tick);
    let mut dirty = true;
    // A key's effect is drawn at once; the link's at most every `LINK_FRAME`.
    let mut urgent = true;
    let frame = LINK_FRAME;
    let mut last_draw = pace::slot_at_or_before(Instant::now());
    // One timer for the next allowed redraw, re-armed only when that time changes.
    let redraw = tokio::time::sleep_until(last_draw + frame);
    tokio::pin!(redraw);
    // Made once: a signal future made afresh on every wake-up costs more than the wake-up.
    let stop_signal = signals.recv();
    tokio::pin!(stop_signal);
    // A link redraw waits while a command's answer is on its way (`awaited_replies`).
    let mut awaited = AwaitedReplies::default();
    let result = loop {
        let holding = awaited.hold_redraw(Instant::now());
        if dirty && (urgent || (last_draw.elapsed() >= frame && !holding)) {
            fleet.sync_overlay();
            if let Err(e) = terminal.draw(|f| ui::render(fleet.app(), f)) {
                break Err(e);
            }
            last_draw = pace::slot_at_or_before(Instant::now());
            dirty = false;
            urgent = false;
        }
        if dirty && redraw.deadline() != last_draw + frame {
            redraw.as_mut().reset(last_draw + frame);
        }
        tokio::select! {
            ev = input_rx.recv() => match ev {
                Some(Ok(ev)) => {
                    if let Err(e) = resize(terminal, &ev) {
                        break Err(e);
                    }
                    // Clicks are mapped against the screen as it is now.
                    fleet.sync_overlay();
                    match fleet::input::action_for(fleet.app(), &ev) {
                        // The loop owns the recording's file: it starts or stops it.
                        Some(Action::ToggleRecording) => {
                            fleet.update(Action::Recording(recorder.toggle()));
                        }
                        Some(a) => fleet.update(a),
                        None => {}
                    }
                    dirty = true;
                    urgent = true;
                }
                Some(Err(e)) => break Err(e),
                None => break Ok(()),
            },
            Some((i, ev)) = next_link_event(links) => {
                // Everything already queued in one go: one wake-up, one redraw decision.
                on_link(fleet, recorder, &mut awaited, i, ev);
                for (i, link) in links.iter_mut().enumerate() {
                    while let Ok(ev) = link.events.try_recv() {
                        on_link(fleet, recorder, &mut awaited, i, ev);
                    }
                }
                // The tap's records carry their own times: taking them here, with the
                // events that follow them, costs no wake-up of its own.
                if let Some(note) = recorder.drain_taps() {
                    fleet.update(Action::Recording(note));
                }
                dirty = true;
            }
            () = &mut tick => {
                let driving = fleet.members.iter().any(|m| m.app.teleop.driving);
                fleet.update(Action::Tick { now_ms: t0.elapsed().as_millis() as u64 });
                dirty |= driving;
                let note = recorder.drain_taps().or_else(|| recorder.tick());
                if let Some(note) = note {
                    fleet.update(Action::Recording(note));
                    dirty = true;
                }
                let driving = fleet.members.iter().any(|m| m.app.teleop.driving);
                let every = if driving { DRIVING_TICK } else { IDLE_TICK };
                tick.as_mut().reset(pace::slot_at_or_before(Instant::now()) + every);
            }
            // While held, the answer's event or the tick (within `awaited_replies::HOLD`)
            // wakes the loop instead.
            () = &mut redraw, if dirty && !holding => {}
            () = &mut stop_signal => break Ok(()),
        }
        // What each robot's app logged, to the recording (while one runs).
        let mut failed = None;
        for (i, m) in fleet.members.iter_mut().enumerate() {
            for line in m.app.take_station_lines() {
                failed = recorder.on_station_log(i, &line).or(failed);
            }
        }
        if let Some(note) = failed {
            fleet.update(Action::Recording(note));
            dirty = true;
        }
        // Each robot's commands and transfers to its own link.
        for (i, (m, link)) in fleet.members.iter_mut().zip(links.iter()).enumerate() {
            for (id, command, when) in m.app.take_outbox_timed() {
                link.handle.submit_when(id, command, when);
                awaited.sent(i, id, Instant::now());
            }
            for t in m.app.transfers.take_frames() {
                link.handle.transfer(t);
            }
        }
        if fleet.quit {
            break Ok(());
        }
    };
    // Dropping the stream wakes and ends crossterm's reader thread.
    reader.abort();
    result
}

/// One link event from robot `i`: to the recorder (connection changes of every link it
/// records: all of them), then to the fleet.
fn on_link(
    fleet: &mut Fleet,
    recorder: &mut TuiRecorder,
    awaited: &mut AwaitedReplies,
    i: usize,
    ev: crate::link::LinkEvent,
) {
    if let crate::link::LinkEvent::CommandDone { id, .. } = &ev {
        awaited.answered(i, *id);
    }
    if let Some(note) = recorder.on_event_of(i, &ev) {
        fleet.update(Action::Recording(note));
    }
    fleet.on_link(i, ev);
}

/// The next event of any link, with its robot's index. No forwarding task: the links are
/// polled in order, and each wake-up drains them all (`event_loop`), so none waits behind
/// another. `None` when every link has ended.
async fn next_link_event(links: &mut [RunningLink]) -> Option<(usize, crate::link::LinkEvent)> {
    std::future::poll_fn(|cx| {
        let mut open = 0;
        for (i, link) in links.iter_mut().enumerate() {
            match link.events.poll_recv(cx) {
                std::task::Poll::Ready(Some(ev)) => return std::task::Poll::Ready(Some((i, ev))),
                std::task::Poll::Ready(None) => {}
                std::task::Poll::Pending => open += 1,
            }
        }
        if open == 0 {
            std::task::Poll::Ready(None)
        } else {
            std::task::Poll::Pending
        }
    })
    .await
}

/// Forwards terminal events from crossterm's event stream until the receiver is gone or the
/// task is aborted (which drops the stream and ends its thread). The stream's thread blocks
/// until an event comes: an idle terminal costs no wake-ups.
pub(crate) fn spawn_reader(
    tx: mpsc::UnboundedSender<io::Result<Event>>,
) -> tokio::task::JoinHandle<()> {
    tokio::spawn(async move {
        let mut events = EventStream::new();
        while let Some(ev) = std::future::poll_fn(|cx| Pin::new(&mut events).poll_next(cx)).await {
            let failed = ev.is_err();
            if tx.send(ev).is_err() || failed {
                return;
            }
        }
    })
}
