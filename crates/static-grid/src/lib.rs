//! Static projected-grid beams (Liktor & Dachsbacher 2010): a regular grid, no refinement, bounding prisms.
