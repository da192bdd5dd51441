//! The model: drag laws (paper Table 1), noise kinds (docs/equations.md,
//! "Noise kinds"), parameters and velocity bounds (Eqs. (5)-(10)).

pub mod atoms;
pub mod capability;
pub mod drag;
pub mod keys;
pub mod noise;
pub mod params;
pub mod reset;
pub(crate) mod shared;
pub mod support_table;

pub use atoms::VelocityAtom;
pub use drag::{Drag, DragLaw, FlowMap};
pub use noise::{Noise, NoiseKind, NoiseModel};
pub use params::{Params, RawParams};
pub use reset::{Reset, ResetRule};
