//! The registry of resetting rules: [`ResetRule`] holds any rule, and
//! [`with_reset!`](crate::with_reset) dispatches to the rule's own type.
//! A new rule is one new file plus one line in the list below.

use super::{NoiseAtReset, Reset, Target};
use serde::{Deserialize, Serialize};

/// The list: `Variant => Type` (Type in [`crate::model::reset`]).
#[doc(hidden)]
#[macro_export]
macro_rules! reset_rules {
    ($cb:ident ($($args:tt)*)) => {
        $crate::$cb! { ($($args)*)
            Poisson => PoissonReset,
            Redrawn => RedrawnReset,
            Random => RandomReset,
        }
    };
}

/// `with_reset!(rule, |r| expr)`: `expr` with `r` bound to the rule's own
/// type, compiled once per rule.
#[macro_export]
macro_rules! with_reset {
    ($rule:expr, |$x:ident| $body:expr) => {
        $crate::reset_rules!(__with_reset_arms($rule, $x, $body))
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __with_reset_arms {
    (($rule:expr, $x:ident, $body:expr) $($variant:ident => $ty:ident,)+) => {
        match $rule {
            $( $crate::model::reset::ResetRule::$variant(ref $x) => $body, )+
        }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __reset_registry {
    (() $($variant:ident => $ty:ident,)+) => {
        /// A resetting rule (see [`crate::model::reset`]).
        #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
        #[serde(tag = "rule", rename_all = "lowercase")]
        pub enum ResetRule {
            $(
                #[doc = concat!("[`", stringify!($ty), "`](super::", stringify!($ty), ")")]
                $variant(super::$ty),
            )+
        }

        impl ResetRule {
            /// The same rule under v → -v.
            fn mirrored_rule(&self) -> Self {
                match self { $(ResetRule::$variant(r) => ResetRule::$variant(r.mirrored()),)+ }
            }
            /// The same rule with another rate.
            fn with_rate_rule(&self, rate: f64) -> Self {
                match self { $(ResetRule::$variant(r) => ResetRule::$variant(r.with_rate(rate)),)+ }
            }
        }
    };
}

crate::reset_rules!(__reset_registry());

impl Reset for ResetRule {
    fn name(&self) -> &'static str {
        crate::with_reset!(self, |r| r.name())
    }
    fn rate(&self) -> f64 {
        crate::with_reset!(self, |r| r.rate())
    }
    fn target(&self) -> Target {
        crate::with_reset!(self, |r| r.target())
    }
    fn noise(&self) -> NoiseAtReset {
        crate::with_reset!(self, |r| r.noise())
    }
    fn mirrored(&self) -> Self {
        self.mirrored_rule()
    }
    fn with_rate(&self, rate: f64) -> Self {
        self.with_rate_rule(rate)
    }
}
