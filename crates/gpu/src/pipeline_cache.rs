//! Shader modules and pipelines compiled once per device.
//!
//! Building a pass compiles its pipelines, which on lavapipe is an LLVM compile of the
//! whole shader: 0.1–5 s per method, paid again every time a method is created. A
//! method created anew for every instant of an animated sequence (`caustics run
//! --animate`) would then report the shader compiler's time as its per-instant setup.
//! A real-time renderer compiles its pipelines once; so does the harness: a pipeline is
//! reused when everything that determines it is the same (the composed WGSL source,
//! entry points, overridable constants, the bind-group layouts of its pipeline layout,
//! and the fixed-function state), and compiled otherwise. Nothing of a method's own
//! work (buffers, bind groups, anything derived from the scene) is shared.
//!
//! A reused pipeline is compatible with bind groups made for a new pass: wgpu
//! deduplicates bind-group layouts by their entries (a pooled layout lives as long as
//! a pipeline layout holds it), so the new pass's identical layouts are the very ones
//! the cached pipeline was built with.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use crate::pass::Reflection;

/// What identifies a compiled pipeline: the composed shader source and a description of
/// everything else its descriptor holds (entry points, constants, layouts, fixed state).
#[derive(Clone, Debug, Hash, PartialEq, Eq)]
pub(crate) struct PipelineKey {
    pub(crate) source: Arc<str>,
    pub(crate) descriptor: String,
}

/// A shader module and its reflection, shared by every [`crate::pass::Shader`] of one source.
type ReflectedModule = (wgpu::ShaderModule, Arc<Reflection>);

/// Pipelines (and shader modules) compiled on one device, by what identifies them.
#[derive(Default)]
pub struct PipelineCache {
    modules: Mutex<HashMap<Arc<str>, ReflectedModule>>,
    render: Mutex<HashMap<PipelineKey, wgpu::RenderPipeline>>,
    compute: Mutex<HashMap<PipelineKey, wgpu::ComputePipeline>>,
    compiled: AtomicU64,
    reused: AtomicU64,
}

/// How many pipelines a device compiled and how many builds found one compiled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PipelineStats {
    /// Pipelines compiled (cache misses).
    pub compiled: u64,
    /// Pipelines reused (cache hits).
    pub reused: u64,
}

impl PipelineStats {
    /// What happened between `earlier` and `self`.
    pub fn since(self, earlier: PipelineStats) -> PipelineStats {
        PipelineStats {
            compiled: self.compiled - earlier.compiled,
            reused: self.reused - earlier.reused,
        }
    }
}

impl PipelineCache {
    /// Counts so far.
    pub fn stats(&self) -> PipelineStats {
        PipelineStats {
            compiled: self.compiled.load(Ordering::Relaxed),
            reused: self.reused.load(Ordering::Relaxed),
        }
    }

    /// The module and reflection of `source`, made by `make` the first time.
    pub(crate) fn module<E>(
        &self,
        source: &Arc<str>,
        make: impl FnOnce() -> Result<(wgpu::ShaderModule, Reflection), E>,
    ) -> Result<ReflectedModule, E> {
        let mut modules = self.modules.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some((module, reflection)) = modules.get(source) {
            return Ok((module.clone(), reflection.clone()));
        }
        let (module, reflection) = make()?;
        let reflection = Arc::new(reflection);
        modules.insert(source.clone(), (module.clone(), reflection.clone()));
        Ok((module, reflection))
    }

    /// The cached render pipeline of `key`, if any (counted as reused).
    pub(crate) fn render(&self, key: &PipelineKey) -> Option<wgpu::RenderPipeline> {
        self.find(&self.render, key)
    }

    /// The cached compute pipeline of `key`, if any (counted as reused).
    pub(crate) fn compute(&self, key: &PipelineKey) -> Option<wgpu::ComputePipeline> {
        self.find(&self.compute, key)
    }

    /// `key`'s pipeline in `pipelines`, counted as reused if there, else as compiled
    /// (the caller compiles it).
    fn find<P: Clone>(
        &self,
        pipelines: &Mutex<HashMap<PipelineKey, P>>,
        key: &PipelineKey,
    ) -> Option<P> {
        let found = pipelines
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .get(key)
            .cloned();
        let counter = if found.is_some() {
            &self.reused
        } else {
            &self.compiled
        };
        counter.fetch_add(1, Ordering::Relaxed);
        found
    }

    /// Keeps render pipelines compiled by a build that succeeded (a build whose error
    /// scope reported an error keeps nothing).
    pub(crate) fn keep_render(&self, compiled: Vec<(PipelineKey, wgpu::RenderPipeline)>) {
        self.render
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .extend(compiled);
    }

    /// [`PipelineCache::keep_render`] for compute pipelines.
    pub(crate) fn keep_compute(&self, compiled: Vec<(PipelineKey, wgpu::ComputePipeline)>) {
        self.compute
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .extend(compiled);
    }
}
