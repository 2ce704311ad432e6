//! `report.json` is the library's ([`snowscape::report`]): typed structs every front end
//! writes the same way.

pub use snowscape::report::*;
