//! The output layer is the library's ([`snowscape::outputs`]): every front end writes through
//! it.

pub use snowscape::outputs::*;
