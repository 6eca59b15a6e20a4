//! Headless wgpu layer of caustics-bench: adapter choice, scene upload, G-buffers, direct lighting, instrumentation, readback.
