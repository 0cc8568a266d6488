//! What every map layer is: the trait a layer implements and the world rectangle it draws
//! into. A leaf below `map` and the layer modules, so that the map and its layers import it
//! and not each other.

use ratatui::widgets::canvas::Context;

use crate::app::App;

/// One kind of thing on the map.
pub trait MapLayer: Sync {
    /// The name used to hide it.
    fn name(&self) -> &'static str;
    /// Paints it; called only when visible.
    fn paint(&self, app: &App, view: &MapView, ctx: &mut Context<'_>);
    /// Whether painting now puts dots on the canvas (not only labels). Only such a layer gets
    /// a canvas layer of its own: each is a copy of the whole canvas, and most of the map's
    /// layers are empty most of the time. Saying yes when painting nothing costs time only.
    fn dots(&self, _app: &App) -> bool {
        true
    }
}

/// The world rectangle being drawn, metres, and the cells it covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapView {
    pub x: [f64; 2],
    pub y: [f64; 2],
    /// Terminal cells across and down (each 2 x 4 braille dots).
    pub cols: u16,
    pub rows: u16,
}
