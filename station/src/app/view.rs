//! Which view the main area shows. A leaf, so that `action` can name a view without importing
//! the app.

/// The main area's content.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Everything that fits, arranged by the terminal's size.
    Dashboard,
    Sensors,
    Charts,
    Map,
    Link,
    Log,
    Params,
}

impl View {
    pub const ALL: [View; 7] = [
        View::Dashboard,
        View::Sensors,
        View::Charts,
        View::Map,
        View::Link,
        View::Log,
        View::Params,
    ];

    pub fn title(&self) -> &'static str {
        match self {
            View::Dashboard => "Dashboard",
            View::Sensors => "Sensors",
            View::Charts => "Charts",
            View::Map => "Map",
            View::Link => "Link",
            View::Log => "Log",
            View::Params => "Parameters",
        }
    }
}
