//! Adaptive beam tracing (Liktor & Dachsbacher 2011): hierarchical projected grid refined by a split oracle, tight 6-triangle hulls, surface and volume caustics.
