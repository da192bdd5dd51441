//! Reset targets behind the [`TargetLaw`] trait: where a reset sends the
//! velocity. One file per target, one registry line
//! ([`reset_targets!`](crate::reset_targets)); every method reads a target
//! through the trait (its draw, its mass on a cell, its moments, its
//! support), so a new kind is picked up by all of them.
//!
//! - [`point`]: a fixed velocity v_r (the paper's Eq. (3)).
//! - [`gaussian`]: a Gaussian truncated to the velocity interval.
//! - [`uniform`]: uniform on [a, b].
//! - [`laplace`]: a two-sided exponential truncated to the velocity interval.

pub mod gaussian;
pub mod laplace;
pub mod point;
pub mod uniform;

pub use gaussian::GaussianTarget;
pub use laplace::LaplaceTarget;
pub use point::PointTarget;
pub use uniform::UniformTarget;

use rand::Rng;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The range check of a location-scale law truncated to (-v_u, v_u) (the
/// Gaussian, the Laplace law): its centre `mean` inside the open interval,
/// its width (`key` = `width`) positive and finite.
pub(crate) fn check_location_scale(
    mean: f64,
    key: &str,
    width: f64,
    vu: f64,
) -> Result<(), String> {
    if !(mean > -vu && mean < vu) {
        return Err(format!(
            "-{vu} < mean < {vu} (the open velocity interval, where the law is truncated)"
        ));
    }
    if !(width > 0.0 && width.is_finite()) {
        return Err(format!("{key} > 0, finite"));
    }
    Ok(())
}

/// A reset target: a probability law Q of the velocity after a reset, on
/// the open velocity interval (-v_u, v_u).
pub trait TargetLaw: Copy + fmt::Debug + PartialEq + Send + Sync {
    /// Its name in a reset spec (`point`, `gauss`).
    const KIND: &'static str;
    /// The keys of its spec, in the order of [`TargetLaw::values`].
    const KEYS: &'static [&'static str];
    /// Built from the spec's values (in [`TargetLaw::KEYS`] order), not yet
    /// checked against the velocity interval.
    fn from_values(values: &[f64]) -> Self;
    /// The spec's values, in [`TargetLaw::KEYS`] order.
    fn values(&self) -> Vec<f64>;
    /// The target checked against (-v_u, v_u) (and truncated to it, where
    /// the law needs it), or the admissible range in words.
    fn fit(&self, v_upper: f64) -> Result<Self, String>;
    /// The fixed velocity of a point target; None for a random one.
    fn point(&self) -> Option<f64> {
        None
    }
    /// (<v_r>, <v_r²>): the moments closed forms need.
    fn moments(&self) -> (f64, f64);
    /// The target under v → -v.
    fn mirrored(&self) -> Self;
    /// Where meshes put a node: the point, the mean of the untruncated
    /// Gaussian, the middle of the support.
    fn centre(&self) -> f64;
    /// The smallest closed interval holding the target's mass.
    fn support(&self) -> (f64, f64);
    /// The probability of [x0, x1) (unnormalised where the law is
    /// truncated; meshes normalise the cell masses by their sum).
    fn mass(&self, x0: f64, x1: f64) -> f64;
    /// ∫_{x0}^{x1} (v - x0) dQ(v), unnormalised like [`TargetLaw::mass`]:
    /// with it, meshes weigh a random target by hat functions (exact for a
    /// piecewise-linear integrand).
    fn moment_from(&self, x0: f64, x1: f64) -> f64;
    /// A velocity drawn from the target.
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64;
}

/// The list: `Variant => Type` (Type in this module).
#[doc(hidden)]
#[macro_export]
macro_rules! reset_targets {
    ($cb:ident ($($args:tt)*)) => {
        $crate::$cb! { ($($args)*)
            Point => PointTarget,
            Gaussian => GaussianTarget,
            Uniform => UniformTarget,
            Laplace => LaplaceTarget,
        }
    };
}

/// `with_target!(target, |t| expr)`: `expr` with `t` bound to the target's
/// own type.
#[macro_export]
macro_rules! with_target {
    ($target:expr, |$x:ident| $body:expr) => {
        $crate::reset_targets!(__with_target_arms($target, $x, $body))
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __with_target_arms {
    (($target:expr, $x:ident, $body:expr) $($variant:ident => $ty:ident,)+) => {
        match $target {
            $( $crate::model::reset::Target::$variant(ref $x) => $body, )+
        }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __target_registry {
    (() $($variant:ident => $ty:ident,)+) => {
        /// Where a reset sends the velocity: any registered [`TargetLaw`].
        #[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
        pub enum Target {
            $(
                #[doc = concat!("[`", stringify!($ty), "`]")]
                $variant($ty),
            )+
        }

        impl Target {
            /// The target of spec kind `kind` from its values, or None for
            /// an unknown kind.
            fn from_kind(kind: &str, values: &[f64]) -> Option<Target> {
                $( if kind == <$ty as TargetLaw>::KIND {
                    return Some(Target::$variant(<$ty>::from_values(values)));
                } )+
                None
            }
            /// The spec keys of kind `kind`.
            fn keys_of(kind: &str) -> Option<&'static [&'static str]> {
                $( if kind == <$ty as TargetLaw>::KIND {
                    return Some(<$ty as TargetLaw>::KEYS);
                } )+
                None
            }
            /// Every kind with its keys, for messages: `point:v=V, ...`.
            pub fn usage() -> String {
                let kinds: Vec<String> = vec![$(
                    format!("{}:{}", <$ty as TargetLaw>::KIND,
                        <$ty as TargetLaw>::KEYS.iter()
                            .map(|k| format!("{k}={}", k.to_uppercase()))
                            .collect::<Vec<_>>().join(","))
                ),+];
                kinds.join(", ")
            }
            /// The kinds, for messages: `point, gauss, ...`.
            pub fn kinds() -> Vec<&'static str> {
                vec![$(<$ty as TargetLaw>::KIND),+]
            }
            /// Its spec kind.
            pub fn kind(&self) -> &'static str {
                match self { $(Target::$variant(_) => <$ty as TargetLaw>::KIND,)+ }
            }
            /// The same target under v → -v.
            pub fn mirrored(&self) -> Target {
                match self { $(Target::$variant(t) => Target::$variant(t.mirrored()),)+ }
            }
            /// Checked against (-v_u, v_u) (see [`TargetLaw::fit`]).
            pub fn fit(&self, v_upper: f64) -> Result<Target, String> {
                match self { $(Target::$variant(t) => t.fit(v_upper).map(Target::$variant),)+ }
            }
        }
    };
}

crate::reset_targets!(__target_registry());

impl Target {
    /// A point target v_r.
    pub fn point(v: f64) -> Target {
        Target::Point(PointTarget { v })
    }
    /// A Gaussian N(mean, std²), truncated to the velocity interval when a
    /// [`crate::Params`] takes it.
    pub fn gauss(mean: f64, std: f64) -> Target {
        Target::Gaussian(GaussianTarget::from_values(&[mean, std]))
    }
    /// Uniform on [a, b].
    pub fn uniform(a: f64, b: f64) -> Target {
        Target::Uniform(UniformTarget { a, b })
    }
    /// The spec values and the keys, for writing a spec.
    pub fn keyed_values(&self) -> Vec<(&'static str, f64)> {
        let keys = Target::keys_of(self.kind()).unwrap_or(&[]);
        keys.iter().copied().zip(self.values()).collect()
    }
    /// A target from a spec's kind and values by key, or the reason it is
    /// not one.
    pub fn parse_kind(kind: &str) -> Result<&'static [&'static str], String> {
        Target::keys_of(kind).ok_or_else(|| {
            format!(
                "a target kind {} (not '{kind}')",
                Target::kinds().join(", ")
            )
        })
    }
    /// The target of `kind` with `values` in its keys' order (the kind
    /// known: [`Target::parse_kind`]).
    pub fn build(kind: &str, values: &[f64]) -> Option<Target> {
        Target::from_kind(kind, values)
    }
    /// The spec values, in its keys' order.
    pub fn values(&self) -> Vec<f64> {
        crate::with_target!(self, |t| t.values())
    }
    /// The fixed velocity of a point target; None for a random one.
    pub fn point_velocity(&self) -> Option<f64> {
        crate::with_target!(self, |t| t.point())
    }
    /// See [`TargetLaw::moments`].
    pub fn moments(&self) -> (f64, f64) {
        crate::with_target!(self, |t| t.moments())
    }
    /// See [`TargetLaw::centre`].
    pub fn centre(&self) -> f64 {
        crate::with_target!(self, |t| t.centre())
    }
    /// See [`TargetLaw::support`].
    pub fn support(&self) -> (f64, f64) {
        crate::with_target!(self, |t| t.support())
    }
    /// See [`TargetLaw::mass`].
    pub fn mass(&self, x0: f64, x1: f64) -> f64 {
        crate::with_target!(self, |t| t.mass(x0, x1))
    }
    /// See [`TargetLaw::moment_from`].
    pub fn moment_from(&self, x0: f64, x1: f64) -> f64 {
        crate::with_target!(self, |t| t.moment_from(x0, x1))
    }
    /// See [`TargetLaw::draw`].
    #[inline]
    pub fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        crate::with_target!(self, |t| t.draw(rng))
    }
}
