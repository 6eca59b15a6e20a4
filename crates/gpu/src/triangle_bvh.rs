//! The scene's triangles (meshes and tessellated heightfields) in one BVH on the GPU,
//! so that a compute pass can trace a ray against the whole scene: analytic objects
//! exactly (`intersect_analytic` of `common.wgsl`), everything else through the BVH
//! (`scene_closest_hit` of [`TRIANGLE_BVH_WGSL`]).
//!
//! The tree is [`obvhs`]'s binary BVH built with PLOC (Meister & Bittner 2018), the
//! crate the CPU reference already uses, flattened to 32-byte nodes: an inner node's
//! children are `first` and `first + 1`, a leaf holds `count` (≤ 8) consecutive
//! triangles. Triangles are stored in leaf order with their vertex normals, so a hit
//! interpolates the shading normal with its barycentrics (DESIGN "Conventions": smooth
//! shading, never flat facets) and also returns the facet's geometric normal, which the
//! adjoint shading-normal factor needs (Veach 1997, §5.3).
//!
//! Built once per scene, on first use ([`crate::GpuScene::triangle_bvh`]), from the
//! same world-space triangles the rasterizer draws.

use std::time::Duration;

use bytemuck::{Pod, Zeroable};
use caustics_scene::{Scene, Shape, TriangleMesh};
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2_from_tris, triangle::Triangle};
use wgpu::util::DeviceExt;

use crate::{GpuContext, GpuError};

/// `BvhNode`, `BvhTriangle`, `TriangleHit`, `bvh_closest_hit`, `adjoint_shading_factor`
/// and, for method passes (it reads `objects` of `frame.wgsl`), `SceneHit` /
/// `scene_closest_hit`. Compose after `frame.wgsl` with [`wgsl`], which puts its two
/// buffers in a group of the caller's choice.
pub const TRIANGLE_BVH_WGSL: &str = include_str!("shaders/triangle_bvh.wgsl");

/// Depth of the traversal stack in `triangle_bvh.wgsl`; a deeper tree is refused at
/// build time rather than traced wrongly.
pub const MAX_DEPTH: u32 = 64;

/// [`TRIANGLE_BVH_WGSL`] with its buffers (`bvh_nodes`, `bvh_triangles`) in `group`.
pub fn wgsl(group: u32) -> String {
    TRIANGLE_BVH_WGSL.replace("@group(BVH_GROUP)", &format!("@group({group})"))
}

/// One node (matches `BvhNode` in triangle_bvh.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct BvhNode {
    /// Box minimum (world, m).
    pub min: [f32; 3],
    /// Triangles of a leaf; 0 for an inner node.
    pub count: u32,
    /// Box maximum (world, m).
    pub max: [f32; 3],
    /// First child (inner node; the second is `first + 1`) or first triangle (leaf).
    pub first: u32,
}

/// One triangle (matches `BvhTriangle` in triangle_bvh.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct BvhTriangle {
    /// Vertex 0 (xyz); w: the owning object's index (as f32, exact below 2^24).
    pub p0: [f32; 4],
    /// Vertex 1.
    pub p1: [f32; 4],
    /// Vertex 2.
    pub p2: [f32; 4],
    /// Unit vertex normals 0, 1, 2 (xyz; w unused).
    pub n0: [f32; 4],
    /// Vertex normal 1.
    pub n1: [f32; 4],
    /// Vertex normal 2.
    pub n2: [f32; 4],
}

/// The flattened tree on the CPU: what [`SceneTriangles`] uploads, and what the tests
/// traverse to check it.
#[derive(Clone, Debug, Default)]
pub struct FlatBvh {
    /// Nodes, root first. A scene without meshes or heightfields has one leaf with a
    /// degenerate triangle.
    pub nodes: Vec<BvhNode>,
    /// Triangles in leaf order.
    pub triangles: Vec<BvhTriangle>,
    /// Longest root-to-leaf path (nodes).
    pub depth: u32,
}

/// True for the shapes that have no closed-form intersection on the GPU and so go
/// into the BVH.
pub fn traced_as_triangles(shape: &Shape) -> bool {
    matches!(shape, Shape::Mesh(_) | Shape::Heightfield(_))
}

impl FlatBvh {
    /// Builds the tree over the triangles of every mesh and heightfield of `scene`
    /// (`meshes` index-aligned with its objects, world space, as in
    /// [`crate::GpuScene::meshes`]).
    pub fn build(scene: &Scene, meshes: &[TriangleMesh]) -> FlatBvh {
        let mut tris = Vec::new();
        let mut records = Vec::new();
        for (object, (o, mesh)) in scene.objects.iter().zip(meshes).enumerate() {
            if !traced_as_triangles(&o.shape) {
                continue;
            }
            for t in 0..mesh.triangle_count() {
                let i = &mesh.indices[3 * t..3 * t + 3];
                let [a, b, c] = mesh.triangle(t);
                tris.push(Triangle {
                    v0: a.into(),
                    v1: b.into(),
                    v2: c.into(),
                });
                let n = |k: usize| mesh.normals[i[k] as usize].extend(0.0).to_array();
                records.push(BvhTriangle {
                    p0: a.extend(object as f32).to_array(),
                    p1: b.extend(0.0).to_array(),
                    p2: c.extend(0.0).to_array(),
                    n0: n(0),
                    n1: n(1),
                    n2: n(2),
                });
            }
        }
        if tris.is_empty() {
            // One leaf holding one degenerate triangle (determinant 0): every ray
            // misses it, and the shader needs no special case.
            return FlatBvh {
                nodes: vec![BvhNode {
                    count: 1,
                    ..BvhNode::default()
                }],
                triangles: vec![BvhTriangle::default()],
                depth: 1,
            };
        }
        let bvh = build_bvh2_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let nodes: Vec<BvhNode> = bvh
            .nodes
            .iter()
            .map(|n| BvhNode {
                min: n.aabb.min.to_array(),
                max: n.aabb.max.to_array(),
                count: n.prim_count,
                first: n.first_index,
            })
            .collect();
        // Leaves index `primitive_indices`; reorder the triangles to that order so the
        // shader needs no indirection.
        let triangles = bvh
            .primitive_indices
            .iter()
            .map(|&k| records[k as usize])
            .collect();
        let depth = tree_depth(&nodes);
        FlatBvh {
            nodes,
            triangles,
            depth,
        }
    }

    /// Closest hit along `o + t·d`, `t_min < t < t_max`, by the same traversal and
    /// triangle test as the shader (Möller–Trumbore): `(t, object)`.
    pub fn closest_hit(
        &self,
        o: [f32; 3],
        d: [f32; 3],
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, u32)> {
        use glam::Vec3;
        let (o, d) = (Vec3::from(o), Vec3::from(d));
        let inv = d.recip();
        let mut best: Option<(f32, u32)> = None;
        let mut t_best = t_max;
        let mut stack = vec![0u32];
        while let Some(k) = stack.pop() {
            let n = &self.nodes[k as usize];
            let t0 = (Vec3::from(n.min) - o) * inv;
            let t1 = (Vec3::from(n.max) - o) * inv;
            let near = t0.min(t1).max_element().max(t_min);
            let far = t0.max(t1).min_element().min(t_best);
            if near > far {
                continue;
            }
            if n.count == 0 {
                stack.extend([n.first, n.first + 1]);
                continue;
            }
            for tri in &self.triangles[n.first as usize..(n.first + n.count) as usize] {
                let corner = |p: &[f32; 4]| Vec3::from_slice(&p[..3]);
                let abc = [corner(&tri.p0), corner(&tri.p1), corner(&tri.p2)];
                if let Some(t) = ray_triangle(o, d, abc).filter(|&t| t > t_min && t < t_best) {
                    t_best = t;
                    best = Some((t, tri.p0[3] as u32));
                }
            }
        }
        best
    }
}

/// Möller–Trumbore, both sides, as `bvh_closest_hit` tests a triangle: the ray
/// parameter t of `o + t·d` through triangle `abc`, or `None` (parallel or outside).
pub fn ray_triangle(o: glam::Vec3, d: glam::Vec3, [a, b, c]: [glam::Vec3; 3]) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then(|| e2.dot(q) / det)
}

fn tree_depth(nodes: &[BvhNode]) -> u32 {
    let mut depth = 0;
    let mut stack = vec![(0u32, 1u32)];
    while let Some((k, d)) = stack.pop() {
        depth = depth.max(d);
        let n = &nodes[k as usize];
        if n.count == 0 {
            stack.extend([(n.first, d + 1), (n.first + 1, d + 1)]);
        }
    }
    depth
}

/// The scene's triangle BVH on the GPU.
pub struct SceneTriangles {
    /// `array<BvhNode>`.
    pub nodes: wgpu::Buffer,
    /// `array<BvhTriangle>`.
    pub triangles: wgpu::Buffer,
    /// Triangles in the tree (0: the scene has only analytic objects).
    pub triangle_count: u32,
    /// Longest root-to-leaf path.
    pub depth: u32,
    /// Bytes of GPU memory the two buffers own.
    pub bytes: u64,
    /// Those bytes in the memory ledger.
    _memory: [crate::limits::Reservation; 2],
}

impl SceneTriangles {
    /// Builds and uploads the tree of `scene`'s meshes and heightfields.
    pub fn upload(
        ctx: &GpuContext,
        scene: &Scene,
        meshes: &[TriangleMesh],
    ) -> Result<Self, GpuError> {
        let flat = FlatBvh::build(scene, meshes);
        if flat.depth > MAX_DEPTH {
            return Err(GpuError::Upload {
                scene: scene.source.clone(),
                message: format!(
                    "its triangle BVH is {} levels deep; the GPU traversal stack holds {MAX_DEPTH}",
                    flat.depth
                ),
            });
        }
        let triangle_count = if scene.objects.iter().any(|o| traced_as_triangles(&o.shape)) {
            flat.triangles.len() as u32
        } else {
            0
        };
        let raise = "use meshes of fewer triangles (--max-scene-triangles bounds them when the scene loads)";
        let memory = [
            ctx.reserve_storage(
                &format!("the scene's triangle BVH nodes ({})", flat.nodes.len()),
                std::mem::size_of_val(flat.nodes.as_slice()) as u64,
                raise,
            )?,
            ctx.reserve_storage(
                &format!(
                    "the scene's triangle BVH triangles ({})",
                    flat.triangles.len()
                ),
                std::mem::size_of_val(flat.triangles.as_slice()) as u64,
                raise,
            )?,
        ];
        let mk = |label: &str, contents: &[u8]| {
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage: wgpu::BufferUsages::STORAGE,
                })
        };
        let (nodes, triangles) = ctx.checked("triangle BVH upload", || {
            (
                mk("scene BVH nodes", bytemuck::cast_slice(&flat.nodes)),
                mk("scene BVH triangles", bytemuck::cast_slice(&flat.triangles)),
            )
        })?;
        Ok(Self {
            bytes: nodes.size() + triangles.size(),
            nodes,
            triangles,
            triangle_count,
            depth: flat.depth,
            _memory: memory,
        })
    }

    /// The two named buffers, for a pass builder's `.bind(group, ..)`.
    pub fn bindings(&self) -> [(&'static str, &wgpu::Buffer); 2] {
        [
            ("bvh_nodes", &self.nodes),
            ("bvh_triangles", &self.triangles),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustics_scene::{Tessellation, Vec3};

    fn builtin(name: &str) -> (Scene, Vec<TriangleMesh>) {
        let path = caustics_scene::resolve(name).expect("built-in scene");
        let scene = Scene::load(&path).expect("scene loads");
        let meshes = scene
            .objects
            .iter()
            .map(|o| o.shape.triangulate(&Tessellation::default()))
            .collect();
        (scene, meshes)
    }

    /// Closest hit over every triangle of the traced shapes, no tree.
    fn brute_force(scene: &Scene, meshes: &[TriangleMesh], o: Vec3, d: Vec3) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        for (object, (obj, mesh)) in scene.objects.iter().zip(meshes).enumerate() {
            if !traced_as_triangles(&obj.shape) {
                continue;
            }
            for t in 0..mesh.triangle_count() {
                if let Some(t) = ray_triangle(o, d, mesh.triangle(t))
                    .filter(|&t| t > 1e-4 && best.is_none_or(|(bt, _)| t < bt))
                {
                    best = Some((t, object as u32));
                }
            }
        }
        best
    }

    /// Deterministic rays from around the scene's specular bounds towards points in it.
    fn rays(scene: &Scene, n: usize) -> Vec<(Vec3, Vec3)> {
        let b = scene.specular_bounds().expect("a specular object");
        let (c, r) = (b.center(), b.bounding_sphere_radius());
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let mut v = || Vec3::new(next(), next(), next()) * 2.0 - Vec3::ONE;
                let o = c + v().normalize_or(Vec3::X) * (2.0 * r);
                let target = c + v() * (0.8 * r);
                (o, (target - o).normalize())
            })
            .collect()
    }

    /// The flattened tree finds the same closest triangle as a search over all of them,
    /// on a bumpy glass mesh and on the mesh cushion (thousands of triangles each).
    #[test]
    fn tree_traversal_matches_brute_force() {
        for name in ["bumpy_glass", "glass_cushion"] {
            let (scene, meshes) = builtin(name);
            let flat = FlatBvh::build(&scene, &meshes);
            assert!(
                flat.triangles.len() > 1000,
                "{name}: {}",
                flat.triangles.len()
            );
            assert!(flat.depth <= MAX_DEPTH, "{name}: depth {}", flat.depth);
            let mut hits = 0;
            for (o, d) in rays(&scene, 2000) {
                let tree = flat.closest_hit(o.to_array(), d.to_array(), 1e-4, f32::MAX);
                let all = brute_force(&scene, &meshes, o, d);
                match (tree, all) {
                    (Some((t1, o1)), Some((t2, o2))) => {
                        assert!((t1 - t2).abs() < 1e-4 && o1 == o2, "{name}: {t1} vs {t2}");
                        hits += 1;
                    }
                    (None, None) => {}
                    other => panic!("{name}: tree and brute force disagree: {other:?}"),
                }
            }
            assert!(hits > 400, "{name}: only {hits} of 2000 rays hit");
        }
    }

    /// A scene of analytic objects only has an empty tree that every ray misses.
    #[test]
    fn analytic_scenes_have_an_empty_tree() {
        let (scene, meshes) = builtin("sphere_on_plane");
        let flat = FlatBvh::build(&scene, &meshes);
        assert_eq!((flat.nodes.len(), flat.triangles.len()), (1, 1));
        assert_eq!(
            flat.closest_hit([0.0, 5.0, 0.0], [0.0, -1.0, 0.0], 0.0, f32::MAX),
            None
        );
    }

    #[test]
    fn wgsl_validates_in_a_method_pass() -> Result<(), String> {
        let src = crate::shader::compose_method(&format!(
            "{}\n@compute @workgroup_size(1) fn k() {{ let h = scene_closest_hit(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0), 0.0, NONE); }}",
            wgsl(2)
        ));
        crate::shader::validate_wgsl("triangle_bvh.wgsl", &src)?;
        crate::assert_wgsl_layout!(
            src.clone(),
            BvhNode {
                min,
                count,
                max,
                first
            }
        );
        crate::assert_wgsl_layout!(
            src,
            BvhTriangle {
                p0,
                p1,
                p2,
                n0,
                n1,
                n2
            }
        );
        Ok(())
    }
}
