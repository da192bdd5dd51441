//! The registry of noise kinds: [`NoiseKind`] names a kind (parse,
//! serialise), and [`with_noise!`](crate::with_noise) is the one dispatch
//! from a [`NoiseKind`] to code monomorphised for that kind's type.
//! Everything here is generated from the one list in [`noise_kinds!`](crate::noise_kinds): a
//! new kind is one line there.

use super::Noise;

/// The registry: one line per kind, `Variant => Type` (Type a struct in
/// [`crate::model::noise`] implementing [`Noise`]; the variant carries its
/// value). Every piece of dispatch is generated from this list by calling
/// back macro `$cb`.
#[doc(hidden)]
#[macro_export]
macro_rules! noise_kinds {
    ($cb:ident ($($args:tt)*)) => {
        $crate::$cb! { ($($args)*)
            kinds [
                Telegraph => Telegraph,
                Rpt => RunPauseTumble,
                States => States,
                None => NoNoise,
            ]
        }
    };
}

/// The one dispatch: `with_noise!(kind, |n| expr)` evaluates `expr` with
/// `n` bound to a reference to the kind's own value, so `expr` is compiled
/// once per kind with static dispatch.
#[macro_export]
macro_rules! with_noise {
    ($kind:expr, |$x:ident| $body:expr) => {
        $crate::noise_kinds!(__with_noise_arms($kind, $x, $body))
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __with_noise_arms {
    (($kind:expr, $x:ident, $body:expr) kinds [$($v:ident => $ty:ident,)*]) => {
        match &$kind {
            $(
                $crate::model::noise::NoiseKind::$v(kind_value) => {
                    let $x: &$crate::model::noise::$ty = kind_value;
                    $body
                }
            )*
        }
    };
}

/// Generates [`NoiseKind`] and its parsing from the list.
#[doc(hidden)]
#[macro_export]
macro_rules! __noise_registry {
    (() kinds [$($v:ident => $ty:ident,)*]) => {
        /// A noise kind shipped with irtp (see [`crate::model::noise`]),
        /// carrying its value.
        #[derive(Clone, Debug, PartialEq)]
        pub enum NoiseKind {
            $(
                #[doc = concat!("[`", stringify!($ty), "`](super::", stringify!($ty), ")")]
                $v(super::$ty),
            )*
        }

        impl NoiseKind {
            /// Every registered kind at its [`Noise::example`], in
            /// registry order.
            pub fn examples() -> Vec<NoiseKind> {
                vec![$(NoiseKind::$v(<super::$ty as Noise>::example()),)*]
            }

            /// The kinds by name, for messages (their syntax is in
            /// `--help` of `--noise`).
            pub fn names() -> String {
                let names: Vec<&str> = vec![$(<super::$ty as Noise>::usage()
                    .split([':', ' '])
                    .next()
                    .unwrap_or_default(),)*];
                names.join(", ")
            }
        }

        impl std::str::FromStr for NoiseKind {
            type Err = $crate::Error;
            /// `telegraph:sigma=3,lambda=0.5`, `none`, ...
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                let (name, args) = match s.split_once(':') {
                    Some((name, args)) => (name.trim(), Some(args)),
                    None => (s.trim(), None),
                };
                $(
                    if name == <super::$ty as Noise>::NAME {
                        return <super::$ty as Noise>::parse(s, args).map(NoiseKind::$v);
                    }
                )*
                Err($crate::Error::invalid("noise", s, format!("one of {}", NoiseKind::names())))
            }
        }
    };
}

crate::noise_kinds!(__noise_registry());

/// Every method of [`Noise`] through the one dispatch (for code that holds
/// a [`NoiseKind`]).
impl NoiseKind {
    /// The kind's name (`telegraph`).
    pub fn name(&self) -> &'static str {
        fn name_of<N: Noise>(_: &N) -> &'static str {
            N::NAME
        }
        crate::with_noise!(self, |n| name_of(n))
    }
    /// The levels a_s.
    pub fn levels(&self) -> Vec<f64> {
        crate::with_noise!(self, |n| n.levels())
    }
    /// The generator Q.
    pub fn generator(&self) -> Vec<Vec<f64>> {
        crate::with_noise!(self, |n| n.generator())
    }
    /// The stationary law π (Eq. (N2)).
    pub fn stationary(&self) -> crate::Result<Vec<f64>> {
        crate::with_noise!(self, |n| n.stationary())
    }
    /// The mirror map ([`Noise::mirror`]).
    pub fn mirror(&self) -> Option<Vec<usize>> {
        crate::with_noise!(self, |n| n.mirror())
    }
    /// (Sigma, lambda) for the paper's symmetric telegraph noise.
    pub fn symmetric_telegraph(&self) -> Option<(f64, f64)> {
        crate::with_noise!(self, |n| n.symmetric_telegraph())
    }
    /// The canonical spec.
    pub fn spec(&self) -> String {
        crate::with_noise!(self, |n| n.write())
    }
}

impl std::fmt::Display for NoiseKind {
    /// The spec.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.spec())
    }
}

impl serde::Serialize for NoiseKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.spec())
    }
}

impl<'de> serde::Deserialize<'de> for NoiseKind {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}
