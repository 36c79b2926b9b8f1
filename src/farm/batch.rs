//! Batches: placeholder, filled in below.
