//! The compute-raster paths' triangle scan conversion (`shader::TRIANGLE_RASTER_WGSL`)
//! against the adapter's rasterizer, triangle by triangle: the same pixels covered but
//! where a pixel centre lies within a hundredth of a pixel of an edge (the rasterizer
//! snaps vertices to its sub-pixel grid, the scan conversion does not), and the same
//! perspective-correct barycentrics within 1e-5, 1e-3 for triangles thinner than a
//! pixel (lavapipe: every pixel the same but two on the sliver's edges, the barycentrics
//! within 4.8e-7, 1.2e-4 and 4.8e-5). Triangles in front of the eye, partly off-screen,
//! in perspective, of both windings, with a vertex behind the eye, past the far plane,
//! edge-on, a few hundredths of a pixel wide (a caustic's focus), and a sliver. On whatever adapter the machine has (lavapipe on CI; without one these
//! fail with the install hint).

use caustics_gpu::readback::{read_buffer_bytes, read_rgba32f};
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{AdapterChoice, GpuContext, shader};

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

/// Clip coordinates of each triangle's three vertices.
const TRIANGLES: [[[f32; 4]; 3]; 10] = [
    // Small, in front, counter-clockwise.
    [
        [-0.31, -0.27, 0.5, 1.0],
        [0.43, -0.11, 0.5, 1.0],
        [0.07, 0.52, 0.5, 1.0],
    ],
    // The same clockwise.
    [
        [-0.31, -0.27, 0.5, 1.0],
        [0.07, 0.52, 0.5, 1.0],
        [0.43, -0.11, 0.5, 1.0],
    ],
    // Large and partly off-screen.
    [
        [-1.7, -0.33, 0.2, 1.0],
        [1.9, -1.4, 0.4, 1.0],
        [0.21, 1.63, 0.6, 1.0],
    ],
    // In perspective: each vertex at its own depth (w 1, 2.5, 4).
    [
        [-0.62, -0.58, 0.3, 1.0],
        [2.05, -0.41, 1.1, 2.5],
        [0.37, 3.12, 2.9, 4.0],
    ],
    // A vertex behind the eye (w < 0): unbounded projection.
    [
        [-0.45, -0.2, 0.4, 1.0],
        [0.33, -0.38, 0.6, 1.3],
        [0.21, 0.55, -0.9, -0.6],
    ],
    // Two vertices behind the eye.
    [
        [0.13, 0.07, 0.5, 0.9],
        [-0.8, 0.3, -0.5, -0.4],
        [0.6, -0.9, -0.7, -0.2],
    ],
    // Past the far plane with one vertex (z > w).
    [
        [-0.52, -0.47, 0.2, 1.0],
        [0.61, -0.3, 1.8, 1.0],
        [0.02, 0.71, 0.9, 1.0],
    ],
    // Edge-on (collinear in projection): nothing.
    [
        [-0.5, -0.5, 0.5, 1.0],
        [0.0, 0.0, 0.5, 1.0],
        [0.5, 0.5, 0.5, 1.0],
    ],
    // A caustic's focus: a triangle a few hundredths of a pixel wide around the centre
    // of pixel (40, 30) (NDC (0.265625, -0.2708333)), in perspective (w 3).
    [
        [0.7963, -0.8130, 1.5, 3.0],
        [0.7983, -0.8120, 1.5, 3.0],
        [0.7970, -0.8110, 1.5, 3.0],
    ],
    // A sliver: 40 pixels long, a twentieth of a pixel wide, across pixel centres.
    [
        [-0.6, 0.1033, 0.5, 1.0],
        [0.65, 0.1066, 0.5, 1.0],
        [0.65, 0.1044, 0.5, 1.0],
    ],
];

/// Draws triangle `t` (the raster path) or scans it for every pixel (the compute path,
/// per pixel: w = 1 covered (+2 if outside the footprint's rectangle, a defect),
/// barycentrics b0 and b1, and the distance in pixels from the centre to the nearest of
/// the triangle's edge lines).
const TEST_WGSL: &str = r#"
@group(0) @binding(0) var<storage, read> clip: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> scanned: array<vec4<f32>>;

struct VsOut {
    @builtin(position) position: vec4<f32>,
    @location(0) bary: vec3<f32>,
}

@vertex
fn vs(@builtin(vertex_index) vi: u32) -> VsOut {
    var o: VsOut;
    o.position = clip[vi];
    let corner = vi % 3u;
    o.bary = vec3<f32>(f32(corner == 0u), f32(corner == 1u), f32(corner == 2u));
    return o;
}

@fragment
fn fs(i: VsOut) -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, i.bary);
}

@compute @workgroup_size(8, 8)
fn scan(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let size = vec2<f32>(f32(groups.x * 8u), f32(groups.y * 8u));
    let t = gid.z;
    let f = triangle_footprint(clip[3u * t], clip[3u * t + 1u], clip[3u * t + 2u], size);
    let b = footprint_barycentrics(f, gid.xy, size);
    let p = vec2<i32>(gid.xy);
    let outside = p.x < f.rect.x || p.x > f.rect.z || p.y < f.rect.y || p.y > f.rect.w;
    let ndc = vec3<f32>(
        (f32(gid.x) + 0.5) / size.x * 2.0 - 1.0,
        1.0 - (f32(gid.y) + 0.5) / size.y * 2.0,
        1.0,
    );
    var distance = 1e30;
    if f.screen == 1u {
        let c = vec2<f32>(gid.xy) + 0.5;
        for (var e = 0u; e < 3u; e++) {
            var a = f.p0;
            var b = f.p1;
            if e == 1u { a = f.p1; b = f.p2; }
            if e == 2u { a = f.p2; b = f.p0; }
            let d = b - a;
            distance = min(distance, abs(d.x * (c.y - a.y) - d.y * (c.x - a.x)) / length(d));
        }
    } else {
        for (var e = 0u; e < 3u; e++) {
            var edge = f.edge0;
            if e == 1u { edge = f.edge1; }
            if e == 2u { edge = f.edge2; }
            let gradient = length(vec2<f32>(2.0 * edge.x / size.x, 2.0 * edge.y / size.y));
            if gradient > 0.0 {
                distance = min(distance, abs(dot(edge, ndc)) / gradient);
            }
        }
    }
    let covered = b.w + select(0.0, 2.0, b.w > 0.0 && outside);
    scanned[(t * u32(size.y) + gid.y) * u32(size.x) + gid.x] = vec4<f32>(covered, b.x, b.y, distance);
}
"#;

#[test]
fn compute_scan_conversion_matches_the_rasterizer() {
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let source = format!("{}\n{TEST_WGSL}", shader::TRIANGLE_RASTER_WGSL);
    shader::validate_wgsl("triangle_raster test", &source).unwrap_or_else(|e| panic!("{e}"));
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("triangle_raster test"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let vertices: Vec<[f32; 4]> = TRIANGLES.iter().flatten().copied().collect();
    let clip = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("clip coordinates"),
        contents: bytemuck::cast_slice(&vertices),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let pixels = (WIDTH * HEIGHT) as usize;
    let scanned_bytes = (TRIANGLES.len() * pixels * 16) as u64;
    let scanned = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("scanned"),
        size: scanned_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let visibility = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::COMPUTE;
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("triangle_raster test"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ],
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("triangle_raster test"),
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: clip.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: scanned.as_entire_binding(),
            },
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("triangle_raster test"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let format = wgpu::TextureFormat::Rgba32Float;
    let raster = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("triangle_raster test raster"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    let scan = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("triangle_raster test scan"),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some("scan"),
        compilation_options: Default::default(),
        cache: None,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&scan);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(WIDTH / 8, HEIGHT / 8, TRIANGLES.len() as u32);
    }
    ctx.queue.submit([encoder.finish()]);
    let scanned: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(
        &read_buffer_bytes(&ctx, &scanned, scanned_bytes, "scanned").expect("readback"),
    );

    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("triangle_raster test target"),
        size: wgpu::Extent3d {
            width: WIDTH,
            height: HEIGHT,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = target.create_view(&Default::default());
    let mut total_covered = 0;
    for (t, triangle) in TRIANGLES.iter().enumerate() {
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("triangle_raster test draw"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&raster);
            pass.set_bind_group(0, &group, &[]);
            let first = 3 * t as u32;
            pass.draw(first..first + 3, 0..1);
        }
        ctx.queue.submit([encoder.finish()]);
        let drawn = read_rgba32f(&ctx, &target, "triangle_raster test target").expect("readback");
        let (mut covered, mut tied, mut worst_bary) = (0usize, 0usize, 0.0f32);
        for p in 0..pixels {
            let hw = &drawn[4 * p..4 * p + 4];
            let cs = scanned[t * pixels + p];
            assert!(
                cs[0] < 2.0,
                "triangle {t} ({triangle:?}): pixel {p} covered outside the footprint's rectangle"
            );
            let (hw_in, cs_in) = (hw[0] > 0.0, cs[0] > 0.0);
            if hw_in != cs_in {
                // Only a centre on an edge (to the rasterizer's sub-pixel precision).
                assert!(
                    cs[3] < 0.01,
                    "triangle {t} ({triangle:?}): pixel ({}, {}) {} by the rasterizer and {} by \
                     the scan, its centre {:.4} px from an edge",
                    p as u32 % WIDTH,
                    p as u32 / WIDTH,
                    if hw_in { "covered" } else { "not covered" },
                    if cs_in { "covered" } else { "not covered" },
                    cs[3]
                );
                tied += 1;
                continue;
            }
            if hw_in {
                covered += 1;
                let b2 = 1.0 - cs[1] - cs[2];
                for (h, c) in hw[1..].iter().zip([cs[1], cs[2], b2]) {
                    worst_bary = worst_bary.max((h - c).abs());
                }
            }
        }
        eprintln!(
            "triangle {t}: {covered} pixels covered by both, {tied} on an edge by one only, \
             worst barycentric difference {worst_bary:.2e}"
        );
        // Triangles thinner than a pixel keep fewer digits on both sides: f32 pixel
        // coordinates near x = 40 resolve 4e-6 px, a fifth of a thousandth of the focus.
        let bound = if t >= 8 { 1e-3 } else { 1e-5 };
        assert!(
            worst_bary < bound,
            "triangle {t} ({triangle:?}): barycentrics differ by {worst_bary}"
        );
        match t {
            // Edge-on: nothing either way.
            7 => assert_eq!(covered + tied, 0, "an edge-on triangle covered pixels"),
            // The focus holds one pixel centre, the sliver a row of them.
            8 => assert_eq!(covered, 1, "the focus triangle"),
            9 => assert!(covered >= 15, "the sliver covered only {covered} pixels"),
            // Every other triangle reaches the viewport.
            _ => assert!(covered > 20, "triangle {t} covered only {covered} pixels"),
        }
        total_covered += covered;
    }
    assert!(total_covered > 3000, "{total_covered}");
}
