//! The registry of drag laws: [`DragLaw`] names a law (parse, serialise), and
//! [`with_drag!`](crate::with_drag) is the one dispatch from a [`DragLaw`] to
//! code monomorphised for that law's type. Everything here is generated from
//! the one list at the bottom of this file: a new law is one line there.

use super::{Drag, FlowMap};

/// The registry: one line per law, `Variant => Type` (Type a unit struct in
/// [`crate::model::drag`] implementing [`Drag`]). Every other piece of
/// dispatch is generated from this list by calling back macro `$cb`.
#[doc(hidden)]
#[macro_export]
macro_rules! drag_laws {
    ($cb:ident ($($args:tt)*)) => {
        $crate::$cb! { ($($args)*)
            Tan => Tan,
            Tanh => Tanh,
            Linear => Linear,
            Cubic => Cubic,
        }
    };
}

/// The one dispatch: `with_drag!(law, |d| expr)` evaluates `expr` with `d`
/// bound to a reference to the law's own type (a unit struct implementing
/// [`Drag`]), so `expr` is compiled once per law with static dispatch.
#[macro_export]
macro_rules! with_drag {
    ($law:expr, |$x:ident| $body:expr) => {
        $crate::drag_laws!(__with_drag_arms($law, $x, $body))
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __with_drag_arms {
    (($law:expr, $x:ident, $body:expr) $($variant:ident => $ty:ident,)+) => {
        match $law {
            $(
                $crate::model::DragLaw::$variant => {
                    let $x = &$crate::model::drag::$ty;
                    $body
                }
            )+
        }
    };
}

/// Generates [`DragLaw`], [`AnyFlow`] and their trait impls from the list.
#[doc(hidden)]
#[macro_export]
macro_rules! __drag_registry {
    (() $($variant:ident => $ty:ident,)+) => {
        /// A drag law shipped with irtp (see [`crate::model::drag`]).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum DragLaw {
            $(
                #[doc = concat!("[`", stringify!($ty), "`](super::", stringify!($ty), ")")]
                $variant,
            )+
        }

        impl DragLaw {
            /// Every law, in registry order.
            pub const ALL: [DragLaw; [$(stringify!($variant)),+].len()] = [$(DragLaw::$variant),+];
        }

        /// The flow of any registered law (for code that holds a
        /// [`DragLaw`]; monomorphised code uses the law's own flow type).
        #[derive(Clone, Debug)]
        pub enum AnyFlow {
            $(
                #[doc = concat!("Flow of [`", stringify!($ty), "`](super::", stringify!($ty), ")")]
                $variant(<super::$ty as Drag>::Flow),
            )+
        }

        impl FlowMap for AnyFlow {
            fn fixed_point(&self) -> f64 {
                match self { $(AnyFlow::$variant(f) => f.fixed_point(),)+ }
            }
            fn rate(&self) -> f64 {
                match self { $(AnyFlow::$variant(f) => f.rate(),)+ }
            }
            fn time(&self, va: f64, vb: f64) -> f64 {
                match self { $(AnyFlow::$variant(f) => f.time(va, vb),)+ }
            }
            fn potential(&self, v: f64) -> f64 {
                match self { $(AnyFlow::$variant(f) => f.potential(v),)+ }
            }
            fn potential_at_distance(&self, u: f64) -> f64 {
                match self { $(AnyFlow::$variant(f) => f.potential_at_distance(u),)+ }
            }
            fn velocity(&self, v0: f64, t: f64) -> f64 {
                match self { $(AnyFlow::$variant(f) => f.velocity(v0, t),)+ }
            }
            fn accelerated(self) -> Self {
                match self { $(AnyFlow::$variant(f) => AnyFlow::$variant(f.accelerated()),)+ }
            }
        }

        impl DragLaw {
            /// The flow of this law with noise value s.
            fn any_flow(&self, s: f64) -> AnyFlow {
                match self { $(DragLaw::$variant => AnyFlow::$variant(super::$ty.flow(s)),)+ }
            }
        }
    };
}

crate::drag_laws!(__drag_registry());

/// Every method through the one dispatch (for code that holds a
/// [`DragLaw`]; engines dispatch once with [`with_drag!`](crate::with_drag)
/// and run monomorphised).
impl Drag for DragLaw {
    type Flow = AnyFlow;
    fn name(&self) -> &'static str {
        crate::with_drag!(self, |d| d.name())
    }
    fn force(&self, v: f64) -> f64 {
        crate::with_drag!(self, |d| d.force(v))
    }
    fn derivative(&self, v: f64) -> f64 {
        crate::with_drag!(self, |d| d.derivative(v))
    }
    fn flow(&self, s: f64) -> AnyFlow {
        self.any_flow(s)
    }
    fn description(&self) -> &'static str {
        crate::with_drag!(self, |d| d.description())
    }
    fn riccati(&self) -> Option<f64> {
        crate::with_drag!(self, |d| d.riccati())
    }
    fn regime_label(&self, sigma: f64, lambda: f64) -> Option<(&'static str, String)> {
        crate::with_drag!(self, |d| d.regime_label(sigma, lambda))
    }
    fn inverse(&self, f: f64) -> f64 {
        crate::with_drag!(self, |d| d.inverse(f))
    }
    fn force_limit(&self) -> f64 {
        crate::with_drag!(self, |d| d.force_limit())
    }
    fn max_derivative(&self, sigma: f64) -> f64 {
        crate::with_drag!(self, |d| d.max_derivative(sigma))
    }
    fn fast_force(&self, v: f64) -> f64 {
        crate::with_drag!(self, |d| d.fast_force(v))
    }
    fn drift(&self, s: f64, v: f64) -> f64 {
        crate::with_drag!(self, |d| d.drift(s, v))
    }
    fn drift_at_distance(&self, s: f64, u: f64) -> f64 {
        crate::with_drag!(self, |d| d.drift_at_distance(s, u))
    }
    fn edge_drift(&self, sigma: f64, x: f64) -> f64 {
        crate::with_drag!(self, |d| d.edge_drift(sigma, x))
    }
    fn flow_time(&self, s: f64, va: f64, vb: f64) -> f64 {
        crate::with_drag!(self, |d| d.flow_time(s, va, vb))
    }
    fn flow_velocity(&self, s: f64, v0: f64, t: f64) -> f64 {
        crate::with_drag!(self, |d| d.flow_velocity(s, v0, t))
    }
    fn flow_deficits(&self, s: f64, va: f64, vb: f64) -> (f64, f64) {
        crate::with_drag!(self, |d| d.flow_deficits(s, va, vb))
    }
    fn flow_displacement(&self, s: f64, v0: f64, t: f64) -> f64 {
        crate::with_drag!(self, |d| d.flow_displacement(s, v0, t))
    }
}

impl DragLaw {
    /// The names accepted by [`str::parse`], comma-separated (for messages).
    pub fn names() -> String {
        DragLaw::ALL
            .iter()
            .map(|d| d.name())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl std::fmt::Display for DragLaw {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for DragLaw {
    type Err = crate::Error;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        DragLaw::ALL
            .iter()
            .copied()
            .find(|d| d.name() == s)
            .ok_or_else(|| crate::Error::invalid("drag", s, format!("one of {}", DragLaw::names())))
    }
}

impl serde::Serialize for DragLaw {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for DragLaw {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}
