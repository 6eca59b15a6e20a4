//! The method contract of caustics-bench: the trait every caustics method implements, its parameters, counters and capabilities.
