//! The station: terminal UI and command line for a robot on a serial link.
