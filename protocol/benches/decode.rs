//! Decode throughput benchmarks (being built, issue 2).
fn main() {}
