//! Benchmarks live in drape.rs; this library is empty on purpose.
