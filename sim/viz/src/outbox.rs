//! Typed channels that encode into one reused buffer and log the bytes.
//!
//! *NOTE*: `foxglove::Channel::log` encodes each message into a 256 KiB buffer on the stack;
//! probing that stack costs about 0.5 µs a message here, more than the MCAP writer's own work
//! (about 0.3 µs). A run logs tens of thousands of messages, so its [`Topic`]s share the
//! buffer of one [`Outbox`] instead and log raw bytes: same schema, same encoding.
//!
//! Writing on a separate thread was tried and measured: on this 2-core machine, with the other
//! core busy, it made runs slower (both threads share one core, and the batches cross caches).

use std::marker::PhantomData;
use std::sync::{Arc, Mutex, PoisonError};

use foxglove::{Context, Encode, PartialMetadata, RawChannel};

/// Makes the [`Topic`]s of one publisher; they share its encoding buffer.
#[derive(Debug, Default)]
pub struct Outbox {
    buffer: Arc<Mutex<Vec<u8>>>,
}

impl Outbox {
    /// The channel `topic` on `context`, with `T`'s schema.
    pub fn topic<T: Encode>(&self, context: &Arc<Context>, topic: impl Into<String>) -> Topic<T> {
        let raw = context.channel_builder(topic).build::<T>().into_inner();
        Topic { raw, buffer: Arc::clone(&self.buffer), kind: PhantomData }
    }
}

/// A channel of messages of type `T` (see the module docs of `viz/outbox.rs`).
pub struct Topic<T> {
    raw: Arc<RawChannel>,
    buffer: Arc<Mutex<Vec<u8>>>,
    kind: PhantomData<fn(&T)>,
}

impl<T: Encode> Topic<T> {
    /// Logs `message` with the log time `ns` (sim time, nanoseconds). Nothing is encoded while
    /// the channel has no sink (a live server without subscribers).
    pub fn log(&self, message: &T, ns: u64) {
        if !self.raw.has_sinks() {
            return;
        }
        let mut buffer = self.buffer.lock().unwrap_or_else(PoisonError::into_inner);
        buffer.clear();
        if message.encode(&mut *buffer).is_ok() {
            self.raw.log_with_meta(&buffer, PartialMetadata::with_log_time(ns));
        }
    }
}
