//! The integration tests of `tests`, one module per topic, linked into one
//! test binary.

mod block_solve;
mod cooperrider;
mod curving;
mod dynamics;
mod equations;
mod equilibrium;
mod freight;
mod freight_train;
mod kik_piotrowski_wheelset;
mod modes;
mod plugins;
mod symbolic;
mod track_frames;
mod train;
mod train_couplers;
mod vehicle2;
mod wheelset_variants;
mod wheelsets;
mod wickens;
