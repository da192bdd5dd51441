//! The registry of drag laws: [`DragLaw`] names a law (parse, serialise), and
//! [`with_drag!`](crate::with_drag) is the one dispatch from a [`DragLaw`] to
//! code monomorphised for that law's type. Everything here is generated from
//! the one list at the bottom of this file: a new law is one line there.

use super::spec::SpecLaw;
use super::{Drag, FlowMap};

/// The registry: one line per law, `Variant => Type`, in two lists. `units`:
/// laws without parameters (Type a unit struct in [`crate::model::drag`]
/// implementing [`Drag`]; the variant is a unit, `DragLaw::Tan`, its spec
/// the bare name `tan`). `params`: laws with a value (Type a `Copy`
/// struct implementing [`Drag`] and [`SpecLaw`], as every
/// [`ParamLaw`](super::ParamLaw) does; the variant carries the law's value,
/// `DragLaw::Power(Power)`, its spec `power:n=0.5,k=1`; the expression law
/// `DragLaw::Expr(Expr)`, `expr:v + 0.3*v^3`). Every
/// other piece of dispatch is generated from this list by calling back
/// macro `$cb`.
#[doc(hidden)]
#[macro_export]
macro_rules! drag_laws {
    ($cb:ident ($($args:tt)*)) => {
        $crate::$cb! { ($($args)*)
            units [
                Tan => Tan,
                Tanh => Tanh,
                Linear => Linear,
                Cubic => Cubic,
            ]
            params [
                Power => Power,
                Carreau => Carreau,
                Coulomb => Coulomb,
                Expr => Expr,
            ]
        }
    };
}

/// The one dispatch: `with_drag!(law, |d| expr)` evaluates `expr` with `d`
/// bound to a reference to the law's own value (the unit struct of a law
/// without parameters, the value carried by the variant of a law with
/// parameters), so `expr` is compiled once per law with static dispatch.
#[macro_export]
macro_rules! with_drag {
    ($law:expr, |$x:ident| $body:expr) => {
        $crate::drag_laws!(__with_drag_arms($law, $x, $body))
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __with_drag_arms {
    (($law:expr, $x:ident, $body:expr)
     units [$($u:ident => $uty:ident,)*] params [$($p:ident => $pty:ident,)*]) => {
        match &$law {
            $(
                $crate::model::DragLaw::$u => {
                    let $x = &$crate::model::drag::$uty;
                    $body
                }
            )*
            $(
                $crate::model::DragLaw::$p(law_value) => {
                    let $x: &$crate::model::drag::$pty = law_value;
                    $body
                }
            )*
        }
    };
}

/// Generates [`DragLaw`], [`AnyFlow`] and their trait impls from the list.
#[doc(hidden)]
#[macro_export]
macro_rules! __drag_registry {
    (() units [$($u:ident => $uty:ident,)*] params [$($p:ident => $pty:ident,)*]) => {
        /// A drag law shipped with irtp (see [`crate::model::drag`]): a unit
        /// variant for a law without parameters, a variant carrying the
        /// law's value for a law with parameters.
        #[derive(Clone, Debug, PartialEq)]
        pub enum DragLaw {
            $(
                #[doc = concat!("[`", stringify!($uty), "`](super::", stringify!($uty), ")")]
                $u,
            )*
            $(
                #[doc = concat!("[`", stringify!($pty), "`](super::", stringify!($pty), ")")]
                $p(super::$pty),
            )*
        }

        impl DragLaw {
            /// Every law without parameters, in registry order.
            pub const ALL: [DragLaw; [$(stringify!($u)),*].len()] = [$(DragLaw::$u),*];

            /// Every registered law in registry order, a law with
            /// a value at its [`SpecLaw::example`].
            pub fn examples() -> Vec<DragLaw> {
                let mut out: Vec<DragLaw> = DragLaw::ALL.to_vec();
                $(out.push(DragLaw::$p(<super::$pty as SpecLaw>::example()));)*
                out
            }

            /// The laws by name, for messages: `tan, ..., power, ...`
            /// (their keys are in `--help` of `--drag`).
            pub fn names() -> String {
                let mut names: Vec<String> = vec![$(super::$uty.name().to_string()),*];
                $(names.push(
                    <super::$pty as SpecLaw>::usage()
                        .split(':')
                        .next()
                        .unwrap_or_default()
                        .to_string(),
                );)*
                names.join(", ")
            }

            /// The spec of this law: its name, with `:key=value,...` for a
            /// law with parameters.
            pub fn spec(&self) -> String {
                match self {
                    $(DragLaw::$u => super::$uty.name().to_string(),)*
                    $(DragLaw::$p(law) => SpecLaw::write(law),)*
                }
            }

            /// The parameters of this law in words (empty for a law
            /// without parameters), for help texts.
            pub fn keys_help(&self) -> String {
                match self {
                    $(DragLaw::$u => String::new(),)*
                    $(DragLaw::$p(_) => <super::$pty as SpecLaw>::keys_help(),)*
                }
            }

            /// The flow of this law with noise value s.
            fn any_flow(&self, s: f64) -> AnyFlow {
                match self {
                    $(DragLaw::$u => AnyFlow::$u(super::$uty.flow(s)),)*
                    $(DragLaw::$p(law) => AnyFlow::$p(law.flow(s)),)*
                }
            }
        }

        impl std::str::FromStr for DragLaw {
            type Err = $crate::Error;
            /// `tan`, or `power:n=0.5,k=1` for a law with parameters.
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                let (name, args) = match s.split_once(':') {
                    Some((name, args)) => (name, Some(args)),
                    None => (s, None),
                };
                $(
                    if name == super::$uty.name() {
                        return match args {
                            None => Ok(DragLaw::$u),
                            Some(_) => Err($crate::Error::invalid(
                                "drag",
                                s,
                                format!("the bare name '{name}' (this law has no parameters)"),
                            )),
                        };
                    }
                )*
                $(
                    if name == <super::$pty as SpecLaw>::example().name() {
                        return <super::$pty as SpecLaw>::parse(s, args).map(DragLaw::$p);
                    }
                )*
                Err($crate::Error::invalid("drag", s, format!("one of {}", DragLaw::names())))
            }
        }

        $crate::__any_flow!($($u => $uty,)* $($p => $pty,)*);
    };
}

/// [`AnyFlow`] over every law of the registry.
#[doc(hidden)]
#[macro_export]
macro_rules! __any_flow {
    ($($variant:ident => $ty:ident,)+) => {
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
    fn static_friction(&self) -> f64 {
        crate::with_drag!(self, |d| d.static_friction())
    }
    fn newtonian(&self) -> bool {
        crate::with_drag!(self, |d| d.newtonian())
    }
    fn two_sided_flow(&self) -> bool {
        crate::with_drag!(self, |d| d.two_sided_flow())
    }
    fn explicit_thermal_step(&self) -> bool {
        crate::with_drag!(self, |d| d.explicit_thermal_step())
    }
    fn thermal_backward(&self) -> Option<f64> {
        crate::with_drag!(self, |d| d.thermal_backward())
    }
    fn evaluation_weight(&self) -> f64 {
        crate::with_drag!(self, |d| d.evaluation_weight())
    }
    fn admissible(&self, sigma: f64) -> crate::error::Result<()> {
        crate::with_drag!(self, |d| d.admissible(sigma))
    }
    fn max_derivative(&self, sigma: f64) -> f64 {
        crate::with_drag!(self, |d| d.max_derivative(sigma))
    }
    fn euler_slope(&self, sigma: f64) -> f64 {
        crate::with_drag!(self, |d| d.euler_slope(sigma))
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

impl std::fmt::Display for DragLaw {
    /// The spec: `tan`, `power:n=0.5,k=1`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.spec())
    }
}

impl serde::Serialize for DragLaw {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.spec())
    }
}

impl<'de> serde::Deserialize<'de> for DragLaw {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}
