//! Slurm: placeholder.
