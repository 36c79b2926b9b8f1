//! Rendering beyond one process: a render split into parts (row bands of the
//! image, ranges of its passes), each written as an OpenEXR part file that
//! names its render, and merged back losslessly; batches of scenes in one
//! process; and job scripts for a batch engine (Slurm) that runs the parts.
//! penumbra schedules nothing itself: the engine does.
//!
//! * [`split`]: which rows a tile `I/N` covers, which passes `A..B` are;
//! * [`identity`]: the hash that says which render a part belongs to;
//! * [`part`]: part files (write, read the header, read the pixels);
//! * [`merge`]: checks a set of parts and streams them into one image;
//! * [`batch`]: list files of scenes and their outputs;
//! * [`slurm`]: the sbatch script for a split render or a batch.

pub mod batch;
pub mod identity;
pub mod merge;
pub mod part;
pub mod slurm;
pub mod split;
