//! Integration tests live in root.rs; this library is empty on purpose.
