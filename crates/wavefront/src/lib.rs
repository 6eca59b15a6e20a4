//! Wallace (2016) wavefront caustics: a refracted light mesh whose brightness is the area ratio from screen-space derivatives.
