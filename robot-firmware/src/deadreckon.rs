//! Compass dead reckoning with bounds validation and beacon calibration (seed 004 §4).
