//! Scene format of caustics-bench: JSON loading, validation, shapes, tessellation, radiometry conventions (no GPU).
