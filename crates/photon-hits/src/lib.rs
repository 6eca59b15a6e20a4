//! Photon hit location images shared by caustic-triangles and splatting: light-space photon paths through specular objects traced against distance maps.
