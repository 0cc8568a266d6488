//! The replay's terminal loop: the live TUI's terminal handling around a `ReplaySession`.
//!
//! Layer: I/O edge (the same terminal setup, event stream, restore on panic and on SIGTERM,
//! SIGHUP and SIGINT as `crate::tui`).
//! The loop sleeps until the next record is due, a key arrives, or the progress bar needs
//! updating (at most every `BAR_REFRESH_US` while playing, never while paused), and draws at
//! most `MAX_FPS` times a second however fast records arrive, so a replay at 128× costs what a
//! live link does. What can fail: terminal I/O (`io::Error`).

use std::io;
use std::time::Duration;

use ratatui::DefaultTerminal;
use tokio::sync::mpsc;
use tokio::time::Instant;

use super::session::ReplaySession;

/// Most frames drawn per second.
pub const MAX_FPS: u64 = 30;

/// Runs the replay until the operator quits. Restores the terminal whatever happens.
pub async fn run(mut session: ReplaySession) -> io::Result<()> {
    let mut signals = crate::tui::StopSignals::new()?;
    crate::tui::install_panic_hook();
    let mut terminal = crate::tui::init_terminal()?;
    let result = event_loop(&mut terminal, &mut session, &mut signals).await;
    crate::tui::restore();
    if let Some(name) = signals.received {
        eprintln!("station: stopped by {name}");
    }
    result
}

async fn event_loop(
    terminal: &mut DefaultTerminal,
    s: &mut ReplaySession,
    signals: &mut crate::tui::StopSignals,
) -> io::Result<()> {
    let size = terminal.size()?;
    s.event(
        0,
        &ratatui::crossterm::event::Event::Resize(size.width, size.height),
    );
    let (input_tx, mut input_rx) = mpsc::unbounded_channel();
    let reader = crate::tui::spawn_reader(input_tx);
    let t0 = Instant::now();
    let wall = || t0.elapsed().as_micros() as u64;
    let frame_us = 1_000_000 / MAX_FPS;
    let mut dirty = true;
    let mut last_draw: Option<u64> = None;
    let mut shown_bar = String::new();
    let stop_signal = signals.recv();
    tokio::pin!(stop_signal);
    let result = loop {
        let now = wall();
        dirty |= s.sync(now);
        // The bar changes every tenth of a second of recording time.
        let bar = super::screen::clock(s.player.position(now));
        if bar != shown_bar {
            shown_bar = bar;
            dirty = true;
        }
        let draw_due = last_draw.is_none_or(|t| now >= t + frame_us);
        if dirty && draw_due {
            if let Err(e) = terminal.draw(|f| s.render(f, now)) {
                break Err(e);
            }
            last_draw = Some(now);
            dirty = false;
        }
        let mut wake = s.next_wake(now);
        if dirty {
            let at = last_draw.map_or(now, |t| t + frame_us);
            wake = Some(wake.map_or(at, |w| w.min(at)));
        }
        let sleep = async {
            match wake {
                Some(w) => tokio::time::sleep_until(t0 + Duration::from_micros(w)).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            ev = input_rx.recv() => match ev {
                Some(Ok(ev)) => {
                    if let Err(e) = crate::tui::resize(terminal, &ev) {
                        break Err(e);
                    }
                    dirty |= s.event(wall(), &ev);
                }
                Some(Err(e)) => break Err(e),
                None => break Ok(()),
            },
            () = sleep => {}
            () = &mut stop_signal => break Ok(()),
        }
        if s.quit {
            break Ok(());
        }
    };
    reader.abort();
    result
}
