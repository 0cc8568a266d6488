//! Reflexive behaviours and their arbitration (seed 000 §4).
