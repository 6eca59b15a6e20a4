//! The caustics-bench harness (the `caustics` binary's library): the method registry,
//! `caustics run` (render, measure, score, write results) and the result schema.
//! The harness owns timing, fill counting and scoring so every method is measured
//! the same way (DESIGN "The method contract").

pub mod machine;
pub mod reference_cmd;
pub mod references;
pub mod registry;
pub mod result;
pub mod run;
pub mod stats;
