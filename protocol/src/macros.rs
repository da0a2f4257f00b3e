//! Crate-internal macros.

/// Declares a `Copy` code enum whose unrecognised wire values survive in an `Unknown(raw)`
/// variant, with `From<raw>` and `From<enum>` conversions in both directions, and a `NAMED` list
/// of its named variants.
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

        impl $name {
            /// Every named variant with its name as spelled in the source (`"Forward"`, …), in
            /// declaration order: for command lines and UIs.
            pub const NAMED: &'static [(&'static str, $name)] = &[$( (stringify!($variant), $name::$variant), )+];
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

/// Implements [`crate::Decoder`] for a decoder type by delegating to its inherent `feed`, `stats`,
/// `buffered` and `reset` (which callers use without importing the trait).
macro_rules! impl_decoder {
    ($decoder:ty, $frame:ty, $error:ty, $stats:ty) => {
        impl $crate::decoder::Decoder for $decoder {
            type Frame = $frame;
            type Error = $error;
            type Stats = $stats;

            fn feed(&mut self, bytes: &[u8]) -> Vec<Result<$frame, $error>> {
                <$decoder>::feed(self, bytes)
            }

            fn stats(&self) -> $stats {
                <$decoder>::stats(self)
            }

            fn buffered(&self) -> usize {
                <$decoder>::buffered(self)
            }

            fn reset(&mut self) {
                <$decoder>::reset(self)
            }
        }
    };
}
