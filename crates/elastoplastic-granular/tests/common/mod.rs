//! Set-ups shared by the crate's tests.

pub mod heap;
