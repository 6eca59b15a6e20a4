//! Caustic triangles (Umenhoffer, Patow, Szirmay-Kalos): photon-hit triangles with per-vertex irradiance drawn into the light's cube map with distance.
