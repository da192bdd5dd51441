//! Parameter sweeps (`irtp_app::sweep`): SLURM arrays, signac ids, the store.

mod signac;
mod slurm;
mod store;
