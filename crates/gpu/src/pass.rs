//! The pass layer: a pass is declared as "this WGSL, these entry points, these named
//! resources", and the wiring lives here once (STYLE 12, after kajiya's
//! `SimpleRenderPass` and bevy's reflected layouts).
//!
//! - [`Shader`] parses and validates the WGSL with naga (the compiler wgpu uses) and
//!   reflects every `@group/@binding` variable: its name, its binding type (uniform,
//!   read-only or read-write storage, texture kind and dimension, sampler) and the
//!   stages of the entry points that use it. Bind-group layouts come from that
//!   reflection, never from hand-written entry lists, so a shader and its layout cannot
//!   drift apart.
//! - Bind groups are made by *name*: `("beams", &beams_buffer)` binds the WGSL variable
//!   `beams`; a missing, unknown or doubly given name is an error naming the pass.
//! - [`ComputePass`] and [`RasterPass`] carry their profiling scope (the pass name
//!   `"<owner>/<pass>"` of [`Frame::compute_pass`] / [`Frame::render_pass`]) and their
//!   bind groups, set when the pass is opened. A raster pass built with
//!   `.counted()` also builds its fill-counting variant (the
//!   `FILL_COUNT` override of `frame.wgsl`) and picks it in count frames.
//! - Group 0 of method passes is the renderer's shared group ([`Renderer::frame_layout`]):
//!   a builder given [`PassBuilder::frame`] takes
//!   that layout for group 0 and binds the renderer's group when the pass opens.
//!
//! ```no_run
//! # use caustics_gpu::{GpuContext, Renderer, Frame, GpuError};
//! # use caustics_gpu::pass::{ComputePass, Shader};
//! # fn f(ctx: &GpuContext, renderer: &Renderer, uniforms: &wgpu::Buffer, out: &wgpu::Buffer,
//! #      frame: &mut Frame<'_>) -> Result<(), GpuError> {
//! let shader = Shader::new(ctx, "my method trace.wgsl", caustics_gpu::shader::compose_method(
//!     "@group(1) @binding(0) var<uniform> params: vec4<f32>;
//!      @group(1) @binding(1) var<storage, read_write> out: array<f32>;
//!      @compute @workgroup_size(64) fn trace(@builtin(global_invocation_id) id: vec3<u32>) {
//!          out[id.x] = params.x;
//!      }"))?;
//! let trace = ComputePass::builder(ctx, "my-method/trace", &shader)
//!     .frame(renderer)
//!     .bind(1, &[("params", uniforms), ("out", out)])
//!     .kernels(&["trace"])
//!     .build()?;
//! // per frame:
//! let mut pass = trace.begin(frame)?;
//! pass.dispatch("trace", [16, 1, 1])?;
//! # Ok(()) }
//! ```

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::ops::{Deref, DerefMut};
use std::sync::Arc;

use crate::frame::{Frame, ProfiledComputePass, ProfiledRenderPass};
use crate::pipeline_cache::PipelineKey;
use crate::renderer::{Renderer, fill_constants};
use crate::{GpuContext, GpuError, shader};

/// One `@group(g) @binding(b)` variable of a shader, as reflected by naga.
#[derive(Clone, Debug, PartialEq)]
pub struct ReflectedBinding {
    /// The WGSL variable's name.
    pub name: String,
    /// Its binding index.
    pub binding: u32,
    /// The binding type the layout needs.
    pub ty: wgpu::BindingType,
    /// The stages of the module's entry points that use it (may be empty).
    pub visibility: wgpu::ShaderStages,
}

/// What naga says of a WGSL source: its bindings per group, entry points and overrides.
#[derive(Clone, Debug, Default)]
pub struct Reflection {
    /// Bindings of each group, by binding index.
    pub groups: BTreeMap<u32, Vec<ReflectedBinding>>,
    /// Entry points and their stage.
    pub entry_points: Vec<(String, wgpu::ShaderStages)>,
    /// Names of pipeline-overridable constants.
    pub overrides: Vec<String>,
}

impl Reflection {
    /// Parses, validates and reflects `source` (no GPU needed).
    pub fn of(label: &str, source: &str) -> Result<Self, String> {
        let (module, info) = shader::parse_and_validate(label, source)?;
        reflect(label, &module, &info)
    }

    /// The bindings of `group`, empty if the shader declares none.
    pub fn group(&self, group: u32) -> &[ReflectedBinding] {
        self.groups.get(&group).map(Vec::as_slice).unwrap_or(&[])
    }

    /// The layout entries of `group`.
    pub fn layout_entries(&self, group: u32) -> Vec<wgpu::BindGroupLayoutEntry> {
        self.group(group)
            .iter()
            .map(|b| wgpu::BindGroupLayoutEntry {
                binding: b.binding,
                visibility: b.visibility,
                ty: b.ty,
                count: None,
            })
            .collect()
    }

    fn stage_of(&self, entry: &str) -> Option<wgpu::ShaderStages> {
        self.entry_points
            .iter()
            .find(|(n, _)| n == entry)
            .map(|(_, s)| *s)
    }
}

fn stage(s: naga::ShaderStage) -> wgpu::ShaderStages {
    match s {
        naga::ShaderStage::Vertex => wgpu::ShaderStages::VERTEX,
        naga::ShaderStage::Fragment => wgpu::ShaderStages::FRAGMENT,
        naga::ShaderStage::Compute => wgpu::ShaderStages::COMPUTE,
        _ => wgpu::ShaderStages::NONE,
    }
}

fn reflect(
    label: &str,
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
) -> Result<Reflection, String> {
    use naga::{AddressSpace, ImageClass, ImageDimension, ScalarKind, TypeInner};
    // Float textures sampled with a filtering sampler in some entry point must be
    // filterable; all others are bound non-filterable (textureLoad works on both).
    let mut filtered = Vec::new();
    for (i, _) in module.entry_points.iter().enumerate() {
        for key in &info.get_entry_point(i).sampling_set {
            let sampler = &module.global_variables[key.sampler];
            if matches!(
                module.types[sampler.ty].inner,
                TypeInner::Sampler { comparison: false }
            ) {
                filtered.push(key.image);
            }
        }
    }
    let mut out = Reflection {
        entry_points: module
            .entry_points
            .iter()
            .map(|e| (e.name.clone(), stage(e.stage)))
            .collect(),
        overrides: module
            .overrides
            .iter()
            .filter_map(|(_, o)| o.name.clone())
            .collect(),
        ..Default::default()
    };
    for (handle, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        let name = var
            .name
            .clone()
            .unwrap_or_else(|| format!("group{}_binding{}", rb.group, rb.binding));
        let inner = &module.types[var.ty].inner;
        let ty = match var.space {
            AddressSpace::Uniform => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            AddressSpace::Storage { access } => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage {
                    read_only: !access.contains(naga::StorageAccess::STORE),
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            AddressSpace::Handle => match inner {
                TypeInner::Sampler { comparison } => wgpu::BindingType::Sampler(if *comparison {
                    wgpu::SamplerBindingType::Comparison
                } else {
                    wgpu::SamplerBindingType::Filtering
                }),
                TypeInner::Image {
                    dim,
                    arrayed,
                    class,
                } => {
                    let view_dimension = match (dim, arrayed) {
                        (ImageDimension::D1, false) => wgpu::TextureViewDimension::D1,
                        (ImageDimension::D2, false) => wgpu::TextureViewDimension::D2,
                        (ImageDimension::D2, true) => wgpu::TextureViewDimension::D2Array,
                        (ImageDimension::D3, false) => wgpu::TextureViewDimension::D3,
                        (ImageDimension::Cube, false) => wgpu::TextureViewDimension::Cube,
                        (ImageDimension::Cube, true) => wgpu::TextureViewDimension::CubeArray,
                        _ => return Err(format!("{label}: {name}: unsupported image dimension")),
                    };
                    match class {
                        ImageClass::Sampled { kind, multi } => wgpu::BindingType::Texture {
                            sample_type: match kind {
                                ScalarKind::Float => wgpu::TextureSampleType::Float {
                                    filterable: filtered.contains(&handle),
                                },
                                ScalarKind::Sint => wgpu::TextureSampleType::Sint,
                                ScalarKind::Uint => wgpu::TextureSampleType::Uint,
                                _ => {
                                    return Err(format!(
                                        "{label}: {name}: unsupported texture sample kind"
                                    ));
                                }
                            },
                            view_dimension,
                            multisampled: *multi,
                        },
                        ImageClass::Depth { multi } => wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Depth,
                            view_dimension,
                            multisampled: *multi,
                        },
                        ImageClass::Storage { format, access } => {
                            wgpu::BindingType::StorageTexture {
                                access: if access.contains(naga::StorageAccess::LOAD)
                                    && access.contains(naga::StorageAccess::STORE)
                                {
                                    wgpu::StorageTextureAccess::ReadWrite
                                } else if access.contains(naga::StorageAccess::STORE) {
                                    wgpu::StorageTextureAccess::WriteOnly
                                } else {
                                    wgpu::StorageTextureAccess::ReadOnly
                                },
                                format: storage_format(*format).ok_or_else(|| {
                                    format!(
                                        "{label}: {name}: unsupported storage format {format:?}"
                                    )
                                })?,
                                view_dimension,
                            }
                        }
                        _ => return Err(format!("{label}: {name}: unsupported image class")),
                    }
                }
                _ => return Err(format!("{label}: {name}: unsupported handle type")),
            },
            other => {
                return Err(format!(
                    "{label}: {name}: address space {other:?} cannot be bound"
                ));
            }
        };
        let mut visibility = wgpu::ShaderStages::NONE;
        for (i, ep) in module.entry_points.iter().enumerate() {
            if !info.get_entry_point(i)[handle].is_empty() {
                visibility |= stage(ep.stage);
            }
        }
        out.groups
            .entry(rb.group)
            .or_default()
            .push(ReflectedBinding {
                name,
                binding: rb.binding,
                ty,
                visibility,
            });
    }
    for bindings in out.groups.values_mut() {
        bindings.sort_by_key(|b| b.binding);
    }
    Ok(out)
}

fn storage_format(f: naga::StorageFormat) -> Option<wgpu::TextureFormat> {
    use naga::StorageFormat as S;
    use wgpu::TextureFormat as T;
    Some(match f {
        S::R32Float => T::R32Float,
        S::R32Uint => T::R32Uint,
        S::R32Sint => T::R32Sint,
        S::Rgba32Float => T::Rgba32Float,
        S::Rgba32Uint => T::Rgba32Uint,
        S::Rgba16Float => T::Rgba16Float,
        S::Rgba8Unorm => T::Rgba8Unorm,
        _ => return None,
    })
}

/// A shader module with its reflection.
pub struct Shader {
    label: String,
    /// The composed WGSL (what identifies the module and, with a descriptor, a cached
    /// pipeline: [`crate::pipeline_cache`]).
    source: Arc<str>,
    module: wgpu::ShaderModule,
    reflection: Arc<Reflection>,
}

impl Shader {
    /// Validates `source` with naga, reflects it and creates the module (once per
    /// device and source: a second shader of the same source shares the first's). A
    /// shader that does not validate is [`GpuError::Shader`] with naga's report.
    pub fn new(ctx: &GpuContext, label: &str, source: String) -> Result<Self, GpuError> {
        let source: Arc<str> = source.into();
        let (module, reflection) = ctx.pipelines().module(&source, || {
            let reflection = Reflection::of(label, &source).map_err(GpuError::Shader)?;
            Ok::<_, GpuError>((shader::module(&ctx.device, label, &source), reflection))
        })?;
        Ok(Self {
            label: label.to_owned(),
            source,
            module,
            reflection,
        })
    }

    /// The module.
    pub fn module(&self) -> &wgpu::ShaderModule {
        &self.module
    }

    /// Its reflection.
    pub fn reflection(&self) -> &Reflection {
        &self.reflection
    }

    /// Its label.
    pub fn label(&self) -> &str {
        &self.label
    }

    fn require_entry(&self, entry: &str, stage: wgpu::ShaderStages) -> Result<(), GpuError> {
        match self.reflection.stage_of(entry) {
            Some(s) if s == stage => Ok(()),
            found => Err(GpuError::Invalid(format!(
                "{}: no {stage:?} entry point {entry:?} (found {:?}); entry points: {}",
                self.label,
                found,
                self.reflection
                    .entry_points
                    .iter()
                    .map(|(n, _)| n.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))),
        }
    }
}

/// A resource that can fill a binding.
pub trait Bindable {
    /// The binding resource.
    fn resource(&self) -> wgpu::BindingResource<'_>;
}

impl Bindable for wgpu::Buffer {
    fn resource(&self) -> wgpu::BindingResource<'_> {
        self.as_entire_binding()
    }
}
impl Bindable for wgpu::TextureView {
    fn resource(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::TextureView(self)
    }
}
impl Bindable for wgpu::Sampler {
    fn resource(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Sampler(self)
    }
}

/// Resources for one bind group, by WGSL variable name.
pub type Named<'r> = [(&'r str, &'r dyn Bindable)];

/// A reflected bind-group layout and the names of its bindings, from which bind
/// groups are made by name.
pub struct BindGroupSchema {
    label: String,
    layout: wgpu::BindGroupLayout,
    bindings: Vec<ReflectedBinding>,
}

impl BindGroupSchema {
    /// The layout of `group` of `shader`.
    pub fn new(device: &wgpu::Device, shader: &Shader, group: u32) -> Self {
        let label = format!("{} group {group}", shader.label);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(&label),
            entries: &shader.reflection.layout_entries(group),
        });
        Self {
            label,
            layout,
            bindings: shader.reflection.group(group).to_vec(),
        }
    }

    /// The layout of `group` of `shader` with the visibility `visibility(binding)`
    /// instead of the stages that use it: for a group shared by passes that are not in
    /// this module (the renderer's group 0, declared in frame.wgsl).
    pub fn with_visibility(
        device: &wgpu::Device,
        shader: &Shader,
        group: u32,
        visibility: impl Fn(&ReflectedBinding) -> wgpu::ShaderStages,
    ) -> Self {
        let label = format!("{} group {group}", shader.label);
        let bindings: Vec<ReflectedBinding> = shader
            .reflection
            .group(group)
            .iter()
            .map(|b| ReflectedBinding {
                visibility: visibility(b),
                ..b.clone()
            })
            .collect();
        let entries: Vec<_> = bindings
            .iter()
            .map(|b| wgpu::BindGroupLayoutEntry {
                binding: b.binding,
                visibility: b.visibility,
                ty: b.ty,
                count: None,
            })
            .collect();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(&label),
            entries: &entries,
        });
        Self {
            label,
            layout,
            bindings,
        }
    }

    /// The layout.
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// A bind group of `resources`, each named as its WGSL variable. Every binding of
    /// the group must be given exactly once.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        resources: &Named<'_>,
    ) -> Result<wgpu::BindGroup, GpuError> {
        for (i, (name, _)) in resources.iter().enumerate() {
            if !self.bindings.iter().any(|b| b.name == *name) {
                return Err(GpuError::Invalid(format!(
                    "{}: the shader has no binding named {name:?}; it has: {}",
                    self.label,
                    self.names()
                )));
            }
            if resources[..i].iter().any(|(n, _)| n == name) {
                return Err(GpuError::Invalid(format!(
                    "{}: binding {name:?} given twice",
                    self.label
                )));
            }
        }
        let mut entries = Vec::with_capacity(self.bindings.len());
        for b in &self.bindings {
            let Some((_, r)) = resources.iter().find(|(n, _)| *n == b.name) else {
                return Err(GpuError::Invalid(format!(
                    "{}: no resource given for binding {:?} (binding {})",
                    self.label, b.name, b.binding
                )));
            };
            entries.push(wgpu::BindGroupEntry {
                binding: b.binding,
                resource: r.resource(),
            });
        }
        Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.label),
            layout: &self.layout,
            entries: &entries,
        }))
    }

    fn names(&self) -> String {
        self.bindings
            .iter()
            .map(|b| b.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The bind groups a pass sets when it opens.
enum GroupSource {
    /// The renderer's group 0 (frame uniforms, camera G-buffer, scene tables, fill counts).
    Frame,
    /// A bind group the pass owns.
    Own(wgpu::BindGroup),
    /// Set by the caller after opening (e.g. one bind group per light view).
    Caller,
}

/// The layouts and bind groups shared by both pass builders.
struct Groups<'a> {
    device: &'a wgpu::Device,
    shader: &'a Shader,
    frame: Option<&'a Renderer>,
    given: BTreeMap<u32, Vec<(&'a str, &'a dyn Bindable)>>,
    caller: Vec<u32>,
}

struct BuiltGroups<'a> {
    pipeline_layout: wgpu::PipelineLayout,
    schemas: BTreeMap<u32, BindGroupSchema>,
    sources: Vec<(u32, GroupSource)>,
    frame: Option<&'a Renderer>,
    groups: u32,
}

/// The layouts of groups `0..groups`, `None` for a group the shader leaves out (or,
/// with `keep`, one not kept).
fn group_layouts<'l>(
    schemas: &'l BTreeMap<u32, BindGroupSchema>,
    frame: Option<&'l Renderer>,
    groups: u32,
    keep: Option<&[u32]>,
) -> Vec<Option<&'l wgpu::BindGroupLayout>> {
    (0..groups)
        .map(|g| {
            if keep.is_some_and(|k| !k.contains(&g)) {
                return None;
            }
            match (g, frame) {
                (0, Some(r)) => Some(r.frame_layout()),
                _ => schemas.get(&g).map(|s| &s.layout),
            }
        })
        .collect()
}

impl BuiltGroups<'_> {
    /// The bind-group layouts' entries (those of `keep`, or all), which with the source
    /// and the rest of a descriptor identify a cached pipeline.
    fn layout_key(&self, keep: Option<&[u32]>) -> String {
        let mut key = String::new();
        for g in 0..self.groups {
            let schema = match (g, self.frame) {
                _ if keep.is_some_and(|k| !k.contains(&g)) => None,
                (0, Some(r)) => Some(r.frame_schema()),
                _ => self.schemas.get(&g),
            };
            // A hole in the pipeline layout is not the same as an empty group.
            let Some(schema) = schema else {
                let _ = write!(key, "[{g}:hole]");
                continue;
            };
            let _ = write!(key, "[{g}:");
            for b in &schema.bindings {
                let _ = write!(key, "({},{:?},{:?})", b.binding, b.visibility, b.ty);
            }
            key.push(']');
        }
        key
    }

    /// A pipeline layout of only the groups in `keep` (the others are holes): for a
    /// kernel that must not see a group the pass's other kernels use.
    fn pipeline_layout_of(
        &self,
        device: &wgpu::Device,
        name: &str,
        keep: &[u32],
    ) -> wgpu::PipelineLayout {
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(name),
            bind_group_layouts: &group_layouts(&self.schemas, self.frame, self.groups, Some(keep)),
            immediate_size: 0,
        })
    }
}

impl<'a> Groups<'a> {
    fn new(device: &'a wgpu::Device, shader: &'a Shader) -> Self {
        Self {
            device,
            shader,
            frame: None,
            given: BTreeMap::new(),
            caller: Vec::new(),
        }
    }

    fn build(self, name: &str) -> Result<BuiltGroups<'a>, GpuError> {
        let declared: Vec<u32> = self.shader.reflection.groups.keys().copied().collect();
        let last = declared.iter().copied().max().map_or(0, |g| g + 1);
        let mut schemas = BTreeMap::new();
        let mut sources = Vec::new();
        for group in 0..last {
            if group == 0 && self.frame.is_some() {
                sources.push((0, GroupSource::Frame));
                continue;
            }
            let schema = BindGroupSchema::new(self.device, self.shader, group);
            if let Some(resources) = self.given.get(&group) {
                let bind = schema.bind(self.device, resources)?;
                sources.push((group, GroupSource::Own(bind)));
            } else if self.caller.contains(&group) {
                sources.push((group, GroupSource::Caller));
            } else if !schema.bindings.is_empty() {
                return Err(GpuError::Invalid(format!(
                    "pass {name}: group {group} of {} ({}) is neither bound nor left to the caller",
                    self.shader.label,
                    schema.names()
                )));
            }
            schemas.insert(group, schema);
        }
        for g in self.given.keys().chain(&self.caller) {
            if !declared.contains(g) {
                return Err(GpuError::Invalid(format!(
                    "pass {name}: {} declares no group {g}",
                    self.shader.label
                )));
            }
        }
        let pipeline_layout = self
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(name),
                bind_group_layouts: &group_layouts(&schemas, self.frame, last, None),
                immediate_size: 0,
            });
        Ok(BuiltGroups {
            pipeline_layout,
            schemas,
            sources,
            frame: self.frame,
            groups: last,
        })
    }
}

fn set_groups<P: SetBindGroup>(pass: &mut P, sources: &[(u32, GroupSource)], renderer: &Renderer) {
    for (group, source) in sources {
        match source {
            GroupSource::Frame => pass.set_group(*group, renderer.frame_bind_group()),
            GroupSource::Own(b) => pass.set_group(*group, b),
            GroupSource::Caller => {}
        }
    }
}

trait SetBindGroup {
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup);
}
impl SetBindGroup for wgpu::ComputePass<'_> {
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup) {
        self.set_bind_group(index, group, &[]);
    }
}
impl SetBindGroup for wgpu::RenderPass<'_> {
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup) {
        self.set_bind_group(index, group, &[]);
    }
}

fn caller_schema<'a>(
    pass: &str,
    schemas: &'a BTreeMap<u32, BindGroupSchema>,
    group: u32,
) -> Result<&'a BindGroupSchema, GpuError> {
    schemas.get(&group).ok_or_else(|| {
        GpuError::Invalid(format!("pass {pass}: its shader declares no group {group}"))
    })
}

/// A compute pass: one profiling scope, its bind groups and one pipeline per kernel
/// (entry point) of one shader.
pub struct ComputePass {
    name: String,
    sources: Vec<(u32, GroupSource)>,
    schemas: BTreeMap<u32, BindGroupSchema>,
    kernels: Vec<(String, wgpu::ComputePipeline)>,
}

/// Declares a pass: the shader's groups (bound, left to the caller, or the renderer's
/// group 0) and, in `spec`, what the kind of pass needs ([`ComputeSpec`],
/// [`RasterSpec`]).
pub struct PassBuilder<'a, S> {
    ctx: &'a GpuContext,
    name: String,
    groups: Groups<'a>,
    spec: S,
}

impl<'a, S> PassBuilder<'a, S> {
    fn new(ctx: &'a GpuContext, name: &str, shader: &'a Shader, spec: S) -> Self {
        Self {
            ctx,
            name: name.to_owned(),
            groups: Groups::new(&ctx.device, shader),
            spec,
        }
    }

    /// Group 0 is the renderer's shared group.
    pub fn frame(mut self, renderer: &'a Renderer) -> Self {
        self.groups.frame = Some(renderer);
        self
    }

    /// Binds `group` to `resources`, each named as its WGSL variable.
    pub fn bind(mut self, group: u32, resources: &[(&'a str, &'a dyn Bindable)]) -> Self {
        self.groups.given.insert(group, resources.to_vec());
        self
    }

    /// `group` is set by the caller after the pass is opened (e.g. one bind group per
    /// light view, made from [`ComputePass::schema`] / [`RasterPass::schema`]).
    pub fn caller_group(mut self, group: u32) -> Self {
        self.groups.caller.push(group);
        self
    }
}

/// What a compute pass declares: its kernels (entry points), constants and, for
/// kernels that must not see every group, the groups they use.
pub struct ComputeSpec<'a> {
    kernels: Vec<&'a str>,
    constants: Vec<(&'a str, f64)>,
    kernel_groups: Vec<(&'a str, Vec<u32>)>,
}

/// Declares a [`ComputePass`].
pub type ComputePassBuilder<'a> = PassBuilder<'a, ComputeSpec<'a>>;

impl ComputePass {
    /// Starts declaring a compute pass named `name` (`"<owner>/<pass>"`) on `shader`.
    pub fn builder<'a>(
        ctx: &'a GpuContext,
        name: &str,
        shader: &'a Shader,
    ) -> ComputePassBuilder<'a> {
        PassBuilder::new(
            ctx,
            name,
            shader,
            ComputeSpec {
                kernels: Vec::new(),
                constants: Vec::new(),
                kernel_groups: Vec::new(),
            },
        )
    }

    /// The profiling scope's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The reflected layout of `group` (for bind groups the caller sets).
    pub fn schema(&self, group: u32) -> Option<&BindGroupSchema> {
        self.schemas.get(&group)
    }

    /// [`Self::schema`] of a group the caller sets (e.g. one bind group per light),
    /// or an error naming the pass when its shader declares no such group.
    pub fn caller_schema(&self, group: u32) -> Result<&BindGroupSchema, GpuError> {
        caller_schema(&self.name, &self.schemas, group)
    }

    /// Opens the pass in `frame` (profiled under its name) with its bind groups set.
    pub fn begin<'f>(&'f self, frame: &'f mut Frame<'_>) -> Result<ComputeRecorder<'f>, GpuError> {
        self.begin_as(frame, &self.name)
    }

    /// [`ComputePass::begin`] profiled under another name: kernels of one shader and
    /// one set of bind groups timed as separate passes (e.g. caustic triangles'
    /// `triangle_areas` and `vertex_irradiance`).
    pub fn begin_as<'f>(
        &'f self,
        frame: &'f mut Frame<'_>,
        name: &str,
    ) -> Result<ComputeRecorder<'f>, GpuError> {
        let renderer = frame.renderer;
        let mut pass = frame.compute_pass(name)?;
        set_groups(&mut *pass, &self.sources, renderer);
        Ok(ComputeRecorder { pass, owner: self })
    }

    fn kernel(&self, name: &str) -> Result<&wgpu::ComputePipeline, GpuError> {
        self.kernels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, p)| p)
            .ok_or_else(|| GpuError::Invalid(format!("pass {}: no kernel {name:?}", self.name)))
    }
}

impl<'a> ComputePassBuilder<'a> {
    /// The entry points to build pipelines for.
    pub fn kernels(mut self, entries: &[&'a str]) -> Self {
        self.spec.kernels.extend_from_slice(entries);
        self
    }

    /// Pipeline-overridable constants for every kernel.
    pub fn constants(mut self, constants: &[(&'a str, f64)]) -> Self {
        self.spec.constants.extend_from_slice(constants);
        self
    }

    /// `kernel`'s pipeline sees only `groups` (the others stay bound but are not part of
    /// its dispatches): e.g. a buffer written as storage by some kernels and read as
    /// indirect arguments by others must not be bound to the latter.
    pub fn kernel_groups(mut self, kernel: &'a str, groups: &[u32]) -> Self {
        self.spec.kernel_groups.push((kernel, groups.to_vec()));
        self
    }

    /// Creates the layouts, bind groups and pipelines (inside a wgpu error scope).
    pub fn build(self) -> Result<ComputePass, GpuError> {
        let shader = self.groups.shader;
        for k in &self.spec.kernels {
            shader.require_entry(k, wgpu::ShaderStages::COMPUTE)?;
        }
        let name = self.name;
        let device = &self.ctx.device;
        let ComputeSpec {
            kernels,
            constants,
            kernel_groups,
        } = self.spec;
        for (k, _) in &kernel_groups {
            if !kernels.contains(k) {
                return Err(GpuError::Invalid(format!(
                    "pass {name}: kernel_groups names {k:?}, which is not one of its kernels"
                )));
            }
        }
        let groups = self.groups;
        let cache = self.ctx.pipelines();
        let (pass, compiled) = self.ctx.checked(&format!("pass {name}"), || {
            let built = groups.build(&name)?;
            let mut compiled = Vec::new();
            let kernels = kernels
                .iter()
                .map(|entry| {
                    let subset = kernel_groups
                        .iter()
                        .find(|(k, _)| k == entry)
                        .map(|(_, g)| g.as_slice());
                    let key = PipelineKey {
                        source: shader.source.clone(),
                        descriptor: format!(
                            "compute {entry} {constants:?} {}",
                            built.layout_key(subset)
                        ),
                    };
                    let pipeline = cache.compute(&key).unwrap_or_else(|| {
                        let layout = subset.map(|g| built.pipeline_layout_of(device, &name, g));
                        let pipeline =
                            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                                label: Some(&format!("{name}:{entry}")),
                                layout: Some(layout.as_ref().unwrap_or(&built.pipeline_layout)),
                                module: &shader.module,
                                entry_point: Some(entry),
                                compilation_options: wgpu::PipelineCompilationOptions {
                                    constants: &constants,
                                    ..Default::default()
                                },
                                cache: None,
                            });
                        compiled.push((key, pipeline.clone()));
                        pipeline
                    });
                    ((*entry).to_owned(), pipeline)
                })
                .collect();
            Ok::<_, GpuError>((
                ComputePass {
                    name: name.clone(),
                    sources: built.sources,
                    schemas: built.schemas,
                    kernels,
                },
                compiled,
            ))
        })??;
        cache.keep_compute(compiled);
        Ok(pass)
    }
}

/// Workgroups for `groups` workgroups of a 1-D kernel as (x, y, 1), x at most 32,768
/// (the device's per-dimension limit is at least 65,535): the kernel reads its linear
/// invocation index as `gid.y · num_workgroups.x · size + gid.x` (size: its workgroup
/// size) and returns past its count.
pub fn groups_2d(groups: u64) -> [u32; 3] {
    let x = groups.clamp(1, 1 << 15);
    [x as u32, groups.div_ceil(x).max(1) as u32, 1]
}

/// An open compute pass; derefs to the wgpu pass for anything not wrapped here.
pub struct ComputeRecorder<'f> {
    pass: ProfiledComputePass<'f>,
    owner: &'f ComputePass,
}

impl ComputeRecorder<'_> {
    /// Dispatches `kernel` over `workgroups`.
    pub fn dispatch(&mut self, kernel: &str, workgroups: [u32; 3]) -> Result<(), GpuError> {
        let pipeline = self.owner.kernel(kernel)?;
        self.pass.set_pipeline(pipeline);
        self.pass
            .dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
        Ok(())
    }

    /// Dispatches `kernel` with workgroup counts read from `args` at `offset`.
    pub fn dispatch_indirect(
        &mut self,
        kernel: &str,
        args: &wgpu::Buffer,
        offset: u64,
    ) -> Result<(), GpuError> {
        let pipeline = self.owner.kernel(kernel)?;
        self.pass.set_pipeline(pipeline);
        self.pass.dispatch_workgroups_indirect(args, offset);
        Ok(())
    }
}

impl<'f> Deref for ComputeRecorder<'f> {
    type Target = wgpu::ComputePass<'f>;
    fn deref(&self) -> &Self::Target {
        &self.pass
    }
}
impl DerefMut for ComputeRecorder<'_> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.pass
    }
}

/// A raster pass: one profiling scope, its bind groups and one render pipeline (two
/// with fill counting: the timed variant and the counting one).
pub struct RasterPass {
    name: String,
    sources: Vec<(u32, GroupSource)>,
    schemas: BTreeMap<u32, BindGroupSchema>,
    timed: wgpu::RenderPipeline,
    counting: Option<wgpu::RenderPipeline>,
    /// Whether the first colour target blends (for the roofline's fill ceiling).
    blended: bool,
}

/// What a raster pass declares: its stages, targets and fixed-function state.
pub struct RasterSpec<'a> {
    vertex: &'a str,
    vertex_buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    fragment: Option<&'a str>,
    targets: Vec<Option<wgpu::ColorTargetState>>,
    primitive: wgpu::PrimitiveState,
    depth_stencil: Option<wgpu::DepthStencilState>,
    counted: bool,
    constants: Vec<(&'a str, f64)>,
}

/// Declares a [`RasterPass`].
pub type RasterPassBuilder<'a> = PassBuilder<'a, RasterSpec<'a>>;

impl RasterPass {
    /// Starts declaring a raster pass named `name` on `shader`, drawing with the
    /// vertex entry point `vertex`.
    pub fn builder<'a>(
        ctx: &'a GpuContext,
        name: &str,
        shader: &'a Shader,
        vertex: &'a str,
    ) -> RasterPassBuilder<'a> {
        PassBuilder::new(
            ctx,
            name,
            shader,
            RasterSpec {
                vertex,
                vertex_buffers: &[],
                fragment: None,
                targets: Vec::new(),
                primitive: wgpu::PrimitiveState {
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: None,
                counted: false,
                constants: Vec::new(),
            },
        )
    }

    /// A full-screen pass: the shared `vs_fullscreen` of `common.wgsl` (one triangle
    /// over the viewport) and `fragment` writing `targets`. Draw it with
    /// [`RasterRecorder::draw_fullscreen`].
    pub fn fullscreen<'a>(
        ctx: &'a GpuContext,
        name: &str,
        shader: &'a Shader,
        fragment: &'a str,
        targets: &[Option<wgpu::ColorTargetState>],
    ) -> RasterPassBuilder<'a> {
        Self::builder(ctx, name, shader, "vs_fullscreen").fragment(fragment, targets)
    }

    /// The profiling scope's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The reflected layout of `group` (for bind groups the caller sets).
    pub fn schema(&self, group: u32) -> Option<&BindGroupSchema> {
        self.schemas.get(&group)
    }

    /// [`Self::schema`] of a group the caller sets (e.g. one bind group per light),
    /// or an error naming the pass when its shader declares no such group.
    pub fn caller_schema(&self, group: u32) -> Result<&BindGroupSchema, GpuError> {
        caller_schema(&self.name, &self.schemas, group)
    }

    /// Opens the pass in `frame` (profiled under its name) on `color` (and `depth`),
    /// with the frame's pipeline variant and the pass's bind groups set.
    pub fn begin<'f>(
        &'f self,
        frame: &'f mut Frame<'_>,
        color: &[Option<wgpu::RenderPassColorAttachment<'_>>],
        depth: Option<wgpu::RenderPassDepthStencilAttachment<'_>>,
    ) -> Result<RasterRecorder<'f>, GpuError> {
        self.begin_as(frame, &self.name, color, depth)
    }

    /// [`RasterPass::begin`] profiled under another name: for a pass that several
    /// owners record (the G-buffer pass of a method's light view is
    /// `"<method>/light_gbuffer"`, the renderer's own is `"base/gbuffer"`).
    pub fn begin_as<'f>(
        &'f self,
        frame: &'f mut Frame<'_>,
        name: &str,
        color: &[Option<wgpu::RenderPassColorAttachment<'_>>],
        depth: Option<wgpu::RenderPassDepthStencilAttachment<'_>>,
    ) -> Result<RasterRecorder<'f>, GpuError> {
        let renderer = frame.renderer;
        let pipeline = match (&self.counting, frame.counting()) {
            (Some(counting), true) => counting,
            _ => &self.timed,
        };
        let mut pass = frame.render_pass_blending(
            name,
            wgpu::RenderPassDescriptor {
                label: None,
                color_attachments: color,
                depth_stencil_attachment: depth,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            },
            self.blended,
        )?;
        pass.set_pipeline(pipeline);
        set_groups(&mut *pass, &self.sources, renderer);
        Ok(RasterRecorder { pass })
    }
}

impl<'a> RasterPassBuilder<'a> {
    /// The fragment entry point and its colour targets.
    pub fn fragment(mut self, entry: &'a str, targets: &[Option<wgpu::ColorTargetState>]) -> Self {
        self.spec.fragment = Some(entry);
        self.spec.targets = targets.to_vec();
        self
    }

    /// Vertex buffer layouts (none: vertices come from `vertex_index` and storage).
    pub fn vertex_buffers(mut self, layouts: &'a [Option<wgpu::VertexBufferLayout<'a>>]) -> Self {
        self.spec.vertex_buffers = layouts;
        self
    }

    /// Primitive state (default: triangle list, no culling).
    pub fn primitive(mut self, primitive: wgpu::PrimitiveState) -> Self {
        self.spec.primitive = primitive;
        self
    }

    /// One-pixel points (a point list, no culling): light that a method could not join
    /// into a triangle or a beam, drawn where it landed (shade it with frame.wgsl's
    /// `point_splat_radiance`).
    pub fn points(self) -> Self {
        self.primitive(wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::PointList,
            ..Default::default()
        })
    }

    /// Orphan points as one-pixel points where `sigma_px` is 0, else as the quads of
    /// frame.wgsl's point kernel (a triangle list of [`point_kernel_vertices`] per point).
    pub fn points_or_kernel_quads(self, sigma_px: f64) -> Self {
        if point_kernel_vertices(sigma_px) == 1 {
            self.points()
        } else {
            self
        }
    }

    /// Depth/stencil state.
    pub fn depth_stencil(mut self, state: wgpu::DepthStencilState) -> Self {
        self.spec.depth_stencil = Some(state);
        self
    }

    /// Also build the fill-counting variant (`FILL_COUNT = true` in frame.wgsl), used
    /// in count frames: every camera-resolution pass that shades fragments.
    pub fn counted(mut self) -> Self {
        self.spec.counted = true;
        self
    }

    /// Pipeline-overridable constants of both stages: a shader specialized at build
    /// time, e.g. on a mode that a uniform would otherwise branch on per fragment
    /// (lavapipe executes both sides of a uniform branch under a mask).
    pub fn constants(mut self, constants: &[(&'a str, f64)]) -> Self {
        self.spec.constants.extend_from_slice(constants);
        self
    }

    /// Creates the layouts, bind groups and pipeline(s) (inside a wgpu error scope).
    pub fn build(self) -> Result<RasterPass, GpuError> {
        let shader = self.groups.shader;
        shader.require_entry(self.spec.vertex, wgpu::ShaderStages::VERTEX)?;
        if let Some(f) = self.spec.fragment {
            shader.require_entry(f, wgpu::ShaderStages::FRAGMENT)?;
        }
        if self.spec.counted
            && !shader
                .reflection
                .overrides
                .iter()
                .any(|o| o == "FILL_COUNT")
        {
            return Err(GpuError::Invalid(format!(
                "pass {}: counted, but {} declares no FILL_COUNT override (compose it with frame.wgsl)",
                self.name, shader.label
            )));
        }
        let name = self.name;
        let device = &self.ctx.device;
        let groups = self.groups;
        let RasterSpec {
            vertex,
            vertex_buffers,
            fragment,
            targets,
            primitive,
            depth_stencil,
            counted,
            constants: own_constants,
        } = self.spec;
        let blended = targets
            .iter()
            .flatten()
            .next()
            .is_some_and(|t| t.blend.is_some());
        let cache = self.ctx.pipelines();
        let (pass, compiled) = self.ctx.checked(&format!("pass {name}"), || {
            let built = groups.build(&name)?;
            let mut compiled = Vec::new();
            let mut pipeline = |fill: &[(&str, f64)]| {
                let constants: Vec<(&str, f64)> =
                    fill.iter().chain(&own_constants).copied().collect();
                let key = PipelineKey {
                    source: shader.source.clone(),
                    descriptor: format!(
                        "render {vertex} {vertex_buffers:?} {fragment:?} {targets:?} {primitive:?} {depth_stencil:?} {constants:?} {}",
                        built.layout_key(None)
                    ),
                };
                if let Some(pipeline) = cache.render(&key) {
                    return pipeline;
                }
                let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(&name),
                    layout: Some(&built.pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &shader.module,
                        entry_point: Some(vertex),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants: &constants,
                            ..Default::default()
                        },
                        buffers: vertex_buffers,
                    },
                    primitive,
                    depth_stencil: depth_stencil.clone(),
                    multisample: Default::default(),
                    fragment: fragment.map(|entry| wgpu::FragmentState {
                        module: &shader.module,
                        entry_point: Some(entry),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants: &constants,
                            ..Default::default()
                        },
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                });
                compiled.push((key, pipeline.clone()));
                pipeline
            };
            let (timed, counting) = if counted {
                (
                    pipeline(&fill_constants(false)),
                    Some(pipeline(&fill_constants(true))),
                )
            } else {
                (pipeline(&[]), None)
            };
            Ok::<_, GpuError>((
                RasterPass {
                    name: name.clone(),
                    sources: built.sources,
                    schemas: built.schemas,
                    timed,
                    counting,
                    blended,
                },
                compiled,
            ))
        })??;
        cache.keep_render(compiled);
        Ok(pass)
    }
}

/// An open raster pass; derefs to the wgpu pass for draws and state.
pub struct RasterRecorder<'f> {
    pass: ProfiledRenderPass<'f>,
}

impl RasterRecorder<'_> {
    /// Draws the full-screen triangle of `vs_fullscreen`.
    pub fn draw_fullscreen(&mut self) {
        self.pass.draw(0..3, 0..1);
    }
}

impl<'f> Deref for RasterRecorder<'f> {
    type Target = wgpu::RenderPass<'f>;
    fn deref(&self) -> &Self::Target {
        &self.pass
    }
}
impl DerefMut for RasterRecorder<'_> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.pass
    }
}

/// Vertices a point takes when drawn with frame.wgsl's point kernel of `sigma_px` camera
/// pixels: the two triangles of its quad, or one (a point) where `sigma_px` is 0.
pub fn point_kernel_vertices(sigma_px: f64) -> u32 {
    if sigma_px > 0.0 { 6 } else { 1 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dispatches_cover_every_workgroup() {
        assert_eq!(groups_2d(0), [1, 1, 1]);
        assert_eq!(groups_2d(100), [100, 1, 1]);
        let [x, y, _] = groups_2d(70_000);
        assert!(u64::from(x) * u64::from(y) >= 70_000 && x <= 1 << 15);
    }

    const SRC: &str = "
        @group(0) @binding(0) var<uniform> u: vec4<f32>;
        @group(0) @binding(1) var<storage, read> input: array<f32>;
        @group(0) @binding(2) var<storage, read_write> output: array<f32>;
        @group(1) @binding(0) var loaded: texture_2d<f32>;
        @group(1) @binding(1) var sampled: texture_2d<f32>;
        @group(1) @binding(2) var linear: sampler;
        @group(1) @binding(3) var ids: texture_2d_array<u32>;
        @group(1) @binding(4) var shadow: texture_depth_2d_array;
        @group(1) @binding(5) var shadow_cmp: sampler_comparison;
        @compute @workgroup_size(1) fn main() { output[0] = input[0] * u.x; }
        @vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
            return vec4<f32>(f32(i), textureLoad(loaded, vec2<i32>(0), 0).x, 0.0, 1.0);
        }
        @fragment fn fs() -> @location(0) vec4<f32> {
            let s = textureSampleLevel(sampled, linear, vec2<f32>(0.5), 0.0);
            let d = textureSampleCompareLevel(shadow, shadow_cmp, vec2<f32>(0.5), 0, 0.5);
            return s + vec4<f32>(f32(textureLoad(ids, vec2<i32>(0), 0, 0).x), d, 0.0, 0.0);
        }";

    #[test]
    fn reflection_gives_types_names_and_stages() -> Result<(), String> {
        let r = Reflection::of("test", SRC)?;
        let g0 = r.group(0);
        assert_eq!(
            g0.iter().map(|b| b.name.as_str()).collect::<Vec<_>>(),
            ["u", "input", "output"]
        );
        assert!(matches!(
            g0[1].ty,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                ..
            }
        ));
        assert!(matches!(
            g0[2].ty,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                ..
            }
        ));
        assert_eq!(g0[0].visibility, wgpu::ShaderStages::COMPUTE);
        let g1 = r.group(1);
        let ty = |n: &str| {
            g1.iter()
                .find(|b| b.name == n)
                .map(|b| (b.ty, b.visibility))
        };
        // textureLoad only: non-filterable; sampled with a filtering sampler: filterable.
        assert_eq!(
            ty("loaded"),
            Some((
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false
                },
                wgpu::ShaderStages::VERTEX
            ))
        );
        assert!(matches!(
            ty("sampled"),
            Some((
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    ..
                },
                wgpu::ShaderStages::FRAGMENT
            ))
        ));
        assert!(matches!(
            ty("ids"),
            Some((
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Uint,
                    view_dimension: wgpu::TextureViewDimension::D2Array,
                    ..
                },
                _
            ))
        ));
        assert!(matches!(
            ty("shadow"),
            Some((
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Depth,
                    ..
                },
                _
            ))
        ));
        assert!(matches!(
            ty("shadow_cmp"),
            Some((
                wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                _
            ))
        ));
        assert!(matches!(
            ty("linear"),
            Some((
                wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                _
            ))
        ));
        assert_eq!(r.stage_of("main"), Some(wgpu::ShaderStages::COMPUTE));
        assert_eq!(r.stage_of("fs"), Some(wgpu::ShaderStages::FRAGMENT));
        Ok(())
    }

    #[test]
    fn method_shaders_reflect_the_frame_group() -> Result<(), String> {
        let r = Reflection::of(
            "frame",
            &shader::compose_method(
                "@compute @workgroup_size(1) fn k() { atomicStore(&fill_counts[0], u32(frame.resolution.x)); }",
            ),
        )?;
        assert!(r.overrides.iter().any(|o| o == "FILL_COUNT"));
        let names: Vec<_> = r.group(0).iter().map(|b| b.name.clone()).collect();
        assert!(names.contains(&"fill_counts".to_owned()), "{names:?}");
        Ok(())
    }
}
