//! The model: drag laws (paper Table 1), parameters and velocity bounds (Eqs. (5)-(10)).

pub mod drag;
pub mod params;
pub mod reset;

pub use drag::{Drag, DragLaw, FlowMap};
pub use params::{Params, RawParams};
pub use reset::{Reset, ResetRule};
