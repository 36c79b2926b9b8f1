//! The benchmark's parts, one module per part, each measured in a child
//! process (`crate::child`) and returned as its struct of `crate::schema`;
//! `knobs`, `drivers` and `profile` run the throughput part in further
//! children.

pub mod cli;
pub mod cpu;
pub mod drivers;
pub mod knobs;
pub mod packet;
pub mod peers;
pub mod profile;
pub mod scaling;
pub mod seminar;
pub mod specialise;
pub mod textures;
pub mod throughput;
