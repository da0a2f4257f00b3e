//! Crate-internal macros.

/// Declares a `Copy` code enum whose unrecognised wire values survive in an `Unknown(raw)`
/// variant, with `From<raw>` and `From<enum>` conversions in both directions.
///
/// `From<raw>` never yields `Unknown(v)` for a `v` that names a known variant; a hand-built
/// `Unknown(v)` with such a `v` converts back to the same raw `v` (and so re-parses as the named
/// variant).
macro_rules! enum_with_unknown {
    (
        $(#[$attr:meta])*
        pub enum $name:ident($repr:ty) {
            $( $(#[$vattr:meta])* $variant:ident = $value:expr ),+ $(,)?
        }
    ) => {
        $(#[$attr])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum $name {
            $( $(#[$vattr])* $variant, )+
            /// A code this crate does not know; the raw wire value is kept.
            Unknown($repr),
        }

        impl ::core::convert::From<$repr> for $name {
            fn from(raw: $repr) -> Self {
                match raw {
                    $( v if v == $value => $name::$variant, )+
                    other => $name::Unknown(other),
                }
            }
        }

        impl ::core::convert::From<$name> for $repr {
            fn from(code: $name) -> Self {
                match code {
                    $( $name::$variant => $value, )+
                    $name::Unknown(raw) => raw,
                }
            }
        }
    };
}
