//! Caustic-mapping baseline: photon hits splatted with a fixed kernel.
