//! WGSL to SPIR-V at run time with naga: assemble the shader tree, resolve the
//! scene's feature `override`s, validate, and write SPIR-V.
//!
//! naga's SPIR-V writer emits no specialisation constants, so the overrides are
//! resolved here with `process_overrides` and each feature set gets its own
//! SPIR-V module (the renderer caches the pipelines by feature set).

use std::fmt;
use std::path::{Path, PathBuf};

use crate::frame::Sampler;
use crate::scene::Features;

pub use super::stages::SHADER_FILES;

/// The ray-query kernel's entry point (`shaders/queries.wgsl`).
pub const TRACE_ENTRY_POINT: &str = "trace";

/// Where the WGSL comes from.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum ShaderSource {
    /// The copy compiled into the binary.
    #[default]
    Embedded,
    /// A directory laid out like `shaders/` (shader development, hot reload).
    Directory(PathBuf),
}

/// One WGSL text made of the shader files, with a map back to them.
#[derive(Clone, Debug)]
pub struct Assembled {
    /// The concatenated source.
    pub text: String,
    /// (file name, first line in `text` (1-based), number of lines).
    pub files: Vec<(String, u32, u32)>,
    /// The file that an error without a place is about (a shade program's
    /// shader file), or `None`: such errors then name "shaders".
    pub subject: Option<String>,
}

/// A WGSL file could not be read, parsed or validated, or SPIR-V not written.
#[derive(Clone, Debug, PartialEq)]
pub struct CompileError {
    /// `file:line:column` of the problem when known, else the file or "shaders".
    pub location: String,
    /// What naga said, with the offending source line and a caret when known.
    pub message: String,
}

impl fmt::Display for CompileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.location, self.message)
    }
}

impl std::error::Error for CompileError {}

impl ShaderSource {
    /// Shader file `name` (relative to `shaders/`): its label for error
    /// messages and its text.
    pub fn read(&self, name: &str) -> Result<(String, String), CompileError> {
        match self {
            ShaderSource::Embedded => {
                let text = super::stages::embedded(name).ok_or_else(|| CompileError {
                    location: format!("shaders/{name}"),
                    message: "no such shader file in the binary".into(),
                })?;
                Ok((format!("shaders/{name}"), text.to_string()))
            }
            ShaderSource::Directory(dir) => {
                let path = dir.join(name);
                let text = std::fs::read_to_string(&path).map_err(|e| CompileError {
                    location: path.display().to_string(),
                    message: format!("cannot read shader: {e}"),
                })?;
                Ok((path.display().to_string(), text))
            }
        }
    }

    /// Reads and concatenates the given shader files.
    pub fn assemble_files(&self, names: &[&str]) -> Result<Assembled, CompileError> {
        let mut out = Assembled {
            text: String::new(),
            files: Vec::new(),
            subject: None,
        };
        for name in names {
            let (label, body) = self.read(name)?;
            out.push_file(label, &body);
        }
        Ok(out)
    }

    /// One module of every engine stage's files (the layout tests, tools and
    /// the render identity read it).
    pub fn assemble(&self) -> Result<Assembled, CompileError> {
        self.assemble_files(&super::stages::engine_files())
    }

    /// The files stage `stage` is compiled from.
    pub fn assemble_stage(&self, stage: super::stages::Stage) -> Result<Assembled, CompileError> {
        self.assemble_files(&stage.files())
    }
}

impl Assembled {
    /// Appends a file's text, labelled `label` in error messages. Each file
    /// starts on a fresh line, whether or not the previous one ends in one.
    pub fn push_file(&mut self, label: String, body: &str) {
        let line = self.text.lines().count() as u32 + 1;
        self.text.push_str(body);
        if !body.ends_with('\n') {
            self.text.push('\n');
        }
        let lines = body.lines().count() as u32;
        self.files.push((label, line, lines));
    }

    /// `file:line:col` for a 1-based line and column of the concatenation.
    fn locate(&self, line: u32, col: u32) -> String {
        for (name, start, count) in &self.files {
            if line >= *start && line < start + count {
                return format!("{name}:{}:{col}", line - start + 1);
            }
        }
        format!("shaders:{line}:{col}")
    }

    /// The file errors without a place are about: the subject, else "shaders".
    fn subject(&self) -> String {
        self.subject.clone().unwrap_or_else(|| "shaders".into())
    }

    /// An error at `loc` of the text, with its line and a caret under it;
    /// columns and caret count characters, not bytes.
    fn error_at(&self, loc: Option<naga::SourceLocation>, message: String) -> CompileError {
        let Some(loc) = loc else {
            return CompileError {
                location: self.subject(),
                message,
            };
        };
        let boundary = |i: usize| crate::wgsl::scan::floor_char_boundary(&self.text, i);
        let start = boundary(loc.offset as usize);
        let end = boundary(start + loc.length as usize);
        let line_start = self.text[..start].rfind('\n').map_or(0, |i| i + 1);
        let line_end = self.text[start..]
            .find('\n')
            .map_or(self.text.len(), |i| start + i);
        let src_line = &self.text[line_start..line_end];
        let column = self.text[line_start..start].chars().count();
        let width = self.text[start..end.min(line_end)].chars().count();
        let caret = " ".repeat(column) + &"^".repeat(width.max(1));
        CompileError {
            location: self.locate(loc.line_number, column as u32 + 1),
            message: format!("{message}\n  {src_line}\n  {caret}"),
        }
    }

    /// Checks every resource the WGSL declares against what the renderer
    /// binds there ([`super::BINDINGS`]): a mismatch (a shader edit that
    /// turns a storage buffer into a uniform, say) would otherwise reach the
    /// driver, which may crash on it.
    fn check_bindings(&self, module: &naga::Module) -> Result<(), CompileError> {
        use crate::vulkan::BindingType as B;
        for (handle, var) in module.global_variables.iter() {
            let Some(rb) = &var.binding else {
                continue;
            };
            let declared = match (var.space, &module.types[var.ty].inner) {
                (naga::AddressSpace::Uniform, _) => Some(B::Uniform),
                (naga::AddressSpace::Storage { access }, _) => {
                    Some(if access.contains(naga::StorageAccess::STORE) {
                        B::StorageReadWrite
                    } else {
                        B::StorageReadOnly
                    })
                }
                (
                    naga::AddressSpace::Handle,
                    naga::TypeInner::Image {
                        dim: naga::ImageDimension::D2,
                        arrayed: false,
                        class:
                            naga::ImageClass::Storage {
                                format: naga::StorageFormat::Rgba32Uint,
                                access,
                            },
                    },
                ) => Some(match access.contains(naga::StorageAccess::STORE) {
                    false => B::TexelImage,
                    // Written (and only written: read-write images need a
                    // device feature), as the stages write theirs.
                    true if !access.contains(naga::StorageAccess::LOAD) => B::StageImage,
                    true => {
                        return self.binding_error(
                            module,
                            handle,
                            "a read-write texel image; declare it `read` or `write`",
                        )
                    }
                }),
                _ => None,
            };
            let info = if rb.group == 0 {
                super::stages::BINDINGS.get(rb.binding as usize)
            } else {
                None
            };
            let expected = info.map(|i| i.ty);
            // A stage may only read a buffer or image others write (same
            // descriptor).
            let fits = match (declared, expected) {
                (Some(B::StorageReadOnly), Some(B::StorageReadWrite)) => true,
                (Some(B::TexelImage), Some(B::StageImage)) => true,
                (d, e) => d.is_some() && d == e,
            };
            let name = var.name.as_deref().unwrap_or("?");
            if fits {
                // The variable's name says what it holds: the table's name,
                // or the shade stage's prefixed one.
                let want = info.map_or("", |i| i.name);
                // (`<name>_out`: the stage that writes a stage image.)
                let out =
                    name.strip_suffix("_out") == Some(want) && declared == Some(B::StageImage);
                if name == want || out || name.strip_prefix("penumbra_") == Some(want) {
                    continue;
                }
                let span = module.global_variables.get_span(handle);
                return Err(self.error_at(
                    span.location(&self.text).into(),
                    format!(
                        "`{name}` at @group(0) @binding({}) is where the renderer binds `{want}`",
                        rb.binding
                    ),
                ));
            }
            let describe = |b: Option<B>| match b {
                Some(B::Uniform) => "a uniform buffer (var<uniform>)",
                Some(B::StorageReadOnly) => "a read-only storage buffer (var<storage, read>)",
                Some(B::StorageReadWrite) => "a storage buffer (var<storage, read_write>)",
                Some(B::TexelImage) => "a texel image (texture_storage_2d<rgba32uint, read>)",
                Some(B::StageImage) => {
                    "a stage's texel image (texture_storage_2d<rgba32uint, write>, or read)"
                }
                None => "nothing",
            };
            let what = if declared.is_some() {
                describe(declared)
            } else {
                "a resource of another kind"
            };
            let message = format!(
                "`{name}` at @group({}) @binding({}) is declared as {what}, but the renderer binds {} there",
                rb.group,
                rb.binding,
                describe(expected)
            );
            let span = module.global_variables.get_span(handle);
            return Err(self.error_at(span.location(&self.text).into(), message));
        }
        Ok(())
    }

    /// An error at the declaration of binding `handle`.
    fn binding_error(
        &self,
        module: &naga::Module,
        handle: naga::Handle<naga::GlobalVariable>,
        what: &str,
    ) -> Result<(), CompileError> {
        let name = module.global_variables[handle]
            .name
            .as_deref()
            .unwrap_or("?");
        let span = module.global_variables.get_span(handle);
        Err(self.error_at(
            span.location(&self.text).into(),
            format!("`{name}` is declared as {what}"),
        ))
    }

    /// Parses the WGSL (no validation): for layout checks and tools.
    pub fn parse(&self) -> Result<naga::Module, CompileError> {
        naga::front::wgsl::parse_str(&self.text)
            .map_err(|e| self.error_at(e.location(&self.text), e.message().to_string()))
    }

    /// Compiles every engine stage of a frame ([`super::stages::Stage::FRAME`])
    /// from this one text and joins their SPIR-V words (tools that measure
    /// or fuzz the compile; the renderer compiles each stage from its own
    /// files).
    pub fn compile_frame(
        &self,
        features: &Features,
        kernel: &KernelOptions,
    ) -> Result<Vec<u32>, CompileError> {
        let mut words = Vec::new();
        let key = StageKernel {
            features: *features,
            settings: Settings::default(),
            options: *kernel,
        };
        for stage in super::stages::Stage::FRAME {
            words.extend(self.compile_entry(&key, stage.entry_point())?);
        }
        Ok(words)
    }

    /// Compiles entry point `entry` (the render kernel or the ray queries).
    /// naga reports bad WGSL as errors, but can panic on some inputs; such a
    /// panic becomes a [`CompileError`] too, so no shader file crashes the
    /// renderer or a `watch` loop.
    ///
    /// It runs on a thread whose stack holds naga's deepest recursion on a
    /// shader file within the limits (crate::wgsl::stack).
    pub fn compile_entry(&self, key: &StageKernel, entry: &str) -> Result<Vec<u32>, CompileError> {
        crate::wgsl::stack::on_parse_stack(|| self.compile_unguarded(key, entry)).unwrap_or_else(
            |panic| {
                Err(CompileError {
                    location: self.subject(),
                    message: format!("internal error in naga ({panic}); please report this shader"),
                })
            },
        )
    }

    /// [`Assembled::compile_entry`] without the panic guard.
    fn compile_unguarded(&self, key: &StageKernel, entry: &str) -> Result<Vec<u32>, CompileError> {
        let kernel = &key.options;
        // The feature values, for overrides or (text specialisation) consts.
        // The general kernel compiles in every scene feature, but not the
        // render settings (pixel jitter changes the image; AOVs need their
        // buffer).
        let values: Vec<(&str, bool)> = override_values(&key.features)
            .into_iter()
            .map(|(name, on)| {
                let on =
                    on || !kernel.specialise || (kernel.with_sampling && name == "HAS_AREA_LIGHTS");
                (name, on)
            })
            .chain(setting_values(&key.settings))
            .collect();
        let module = if kernel.text_specialise {
            // The alternative to overrides: write the values into the WGSL
            // text as plain constants before naga sees it.
            let mut text = self.clone();
            for (name, on) in &values {
                text.text = text.text.replace(
                    &format!("override {name}: bool = true;"),
                    &format!("const {name}: bool = {on};"),
                );
            }
            text.parse()?
        } else {
            self.parse()?
        };
        let info = validator().validate(&module).map_err(|e| {
            self.error_at(
                e.location(&self.text),
                crate::wgsl::reflect::error_chain(e.as_inner()),
            )
        })?;
        self.check_bindings(&module)?;
        let mut constants = naga::back::PipelineConstants::default();
        if !kernel.text_specialise {
            for (name, on) in values {
                constants.insert(name.to_string(), if on { 1.0 } else { 0.0 });
            }
        }
        let bvh = kernel.accel == Accel::Bvh;
        constants.insert("USE_BVH".into(), if bvh { 1.0 } else { 0.0 });
        let packet = kernel.traversal == Traversal::Packet;
        constants.insert("PACKET_TRAVERSAL".into(), if packet { 1.0 } else { 0.0 });
        constants.insert("TRIANGLE_TEST".into(), kernel.triangle_test as u32 as f64);
        let epsilon = match kernel.shadow_offset {
            ShadowOffset::Robust => 0.0,
            ShadowOffset::Fixed(e) => e as f64,
        };
        constants.insert("SHADOW_EPSILON".into(), epsilon);
        constants.insert("SAMPLER".into(), kernel.sampler as u32 as f64);
        // The shade stage's overrides ([`shade_override_values`]), and its
        // names for the settings it depends on.
        for (name, on) in shade_override_values(&key.features) {
            let on = on || !kernel.specialise;
            constants.insert(name.into(), if on { 1.0 } else { 0.0 });
        }
        for (name, on) in shade_setting_values(&key.settings) {
            constants.insert(name.into(), if on { 1.0 } else { 0.0 });
        }
        // Each stage declares only the overrides its files use; naga refuses
        // values for any other.
        constants.retain(|name, _| {
            module
                .overrides
                .iter()
                .any(|(_, o)| o.name.as_deref() == Some(name.as_str()))
        });
        let (module, info) = naga::back::pipeline_constants::process_overrides(
            &module,
            &info,
            Some((naga::ShaderStage::Compute, entry)),
            &constants,
        )
        .map_err(|e| CompileError {
            location: self.subject(),
            message: e.to_string(),
        })?;
        // What the overrides switched off goes before the driver sees it
        // (render::prune says why). Pruning only removes code: should it
        // ever fail or panic (a bug of ours), a release build compiles the
        // unpruned module, and a debug build (the tests) fails loudly.
        let pruned = crate::panics::catch(|| super::prune::prune(module.as_ref().clone()));
        let (module, info) = match pruned {
            Ok(Ok((module, info, _))) => (module, info),
            Ok(Err(e)) | Err(e) => {
                if cfg!(debug_assertions) {
                    panic!("pruning failed: {e}");
                }
                (module.into_owned(), info.into_owned())
            }
        };
        let options = spirv_options(entry == super::shade::SHADE_ENTRY_POINT);
        let pipeline = naga::back::spv::PipelineOptions {
            shader_stage: naga::ShaderStage::Compute,
            entry_point: entry.to_string(),
        };
        naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline))
            .map(super::spirv::forbid_contraction)
            .map_err(|e| CompileError {
                location: self.subject(),
                message: e.to_string(),
            })
    }
}

/// naga's validator with the flags and capabilities of the renderer's
/// modules (also what a user's shader file is validated with when it is
/// read, crate::wgsl).
pub fn validator() -> naga::valid::Validator {
    use naga::valid::{Capabilities, ValidationFlags, Validator};
    let mut validator = Validator::new(
        ValidationFlags::all(),
        // 64-bit integers for the stage words (render.wgsl's
        // `stage_words`); a module without them declares no Int64
        // capability (pruning drops them with STAGE_WORDS off).
        Capabilities::IMMEDIATES | Capabilities::SUBGROUP | Capabilities::SHADER_INT64,
    );
    // Subgroup sums for the ray counters; the Vulkan context only offers
    // devices that support them in compute shaders.
    validator
        .subgroup_stages(naga::valid::ShaderStages::COMPUTE)
        .subgroup_operations(
            naga::valid::SubgroupOperationSet::BASIC
                | naga::valid::SubgroupOperationSet::ARITHMETIC
                | naga::valid::SubgroupOperationSet::VOTE
                | naga::valid::SubgroupOperationSet::BALLOT,
        );
    validator
}

/// How the kernel finds the nearest sphere or triangle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Accel {
    /// Traverse a bounding volume hierarchy (the default).
    #[default]
    Bvh,
    /// Test every primitive (the baseline the BVH is measured against).
    BruteForce,
}

/// How the lanes of a subgroup walk the BVH (primary rays in the hit
/// stage, shadow rays in the hit and shadow stages, ray queries).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Traversal {
    /// Each lane walks the tree for its own ray, loading its records as
    /// texels (the default).
    #[default]
    PerLane,
    /// The lanes walk it together: the node is the same for every lane
    /// (`subgroupBroadcastFirst`), its record a storage-buffer load at a
    /// subgroup-uniform index, each lane testing its own ray against the
    /// node's children (`shaders/bvh.wgsl`, `PACKET_TRAVERSAL`;
    /// docs/stages.md measures it).
    Packet,
}

/// The ray/triangle test.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TriangleTest {
    /// Möller–Trumbore in the seminar's order: u, then v, then t, rejecting
    /// early. Not watertight: rays can slip through shared edges.
    UvFirst = 0,
    /// Möller–Trumbore computing t first (the seminar's slower baseline).
    TFirst = 1,
    /// Woop, Benthin and Wald's watertight test (JCGT 2013), also in the
    /// seminar's order: edge functions (barycentrics) first, t last. The
    /// default: no ray slips between triangles that share an edge.
    #[default]
    Watertight = 2,
}

/// Where shadow rays start.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum ShadowOffset {
    /// Skip the primitive the ray starts on, decide a sphere's own shadow
    /// exactly, and start triangle rays a few ulps off the surface
    /// (`shaders/shadows.wgsl`): no acne and no leaks (the default).
    #[default]
    Robust,
    /// The classic alternative: start `epsilon` world units along the normal
    /// (turned to the viewer) and test every primitive. Used to compare with
    /// other renderers set up that way.
    Fixed(f32),
}

impl Eq for ShadowOffset {}

impl std::hash::Hash for ShadowOffset {
    fn hash<H: std::hash::Hasher>(&self, h: &mut H) {
        match self {
            ShadowOffset::Robust => 0u32.hash(h),
            ShadowOffset::Fixed(e) => e.to_bits().hash(h),
        }
    }
}

/// Kernel variants a user chooses (as opposed to features a scene implies).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct KernelOptions {
    /// BVH or brute force.
    pub accel: Accel,
    /// Per-lane or packet BVH traversal.
    pub traversal: Traversal,
    /// Order of the ray/triangle test.
    pub triangle_test: TriangleTest,
    /// Where shadow rays start.
    pub shadow_offset: ShadowOffset,
    /// How samples are placed (scenes with area lights or several samples
    /// per pixel).
    pub sampler: Sampler,
    /// Compile only the features the scene uses (true, the default), or the
    /// general kernel with every feature override on (false: the baseline
    /// the benchmark measures specialisation against).
    pub specialise: bool,
    /// Compile the area-light sampling code in even when the scene has no
    /// area light (the baseline the benchmark measures its cost against).
    pub with_sampling: bool,
    /// Specialise by writing the feature values into the WGSL text as
    /// `const`s instead of resolving `override`s (the benchmark compares the
    /// two).
    pub text_specialise: bool,
}

impl Default for KernelOptions {
    fn default() -> Self {
        KernelOptions {
            accel: Accel::default(),
            traversal: Traversal::default(),
            triangle_test: TriangleTest::default(),
            shadow_offset: ShadowOffset::default(),
            sampler: Sampler::default(),
            specialise: true,
            with_sampling: false,
            text_specialise: false,
        }
    }
}

impl std::str::FromStr for Accel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "bvh" => Ok(Accel::Bvh),
            "brute-force" => Ok(Accel::BruteForce),
            _ => Err(format!("expected `bvh` or `brute-force`, got `{s}`")),
        }
    }
}

impl std::str::FromStr for Traversal {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "per-lane" => Ok(Traversal::PerLane),
            "packet" => Ok(Traversal::Packet),
            _ => Err(format!("expected `per-lane` or `packet`, got `{s}`")),
        }
    }
}

impl std::str::FromStr for TriangleTest {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "uv-first" => Ok(TriangleTest::UvFirst),
            "t-first" => Ok(TriangleTest::TFirst),
            "watertight" => Ok(TriangleTest::Watertight),
            _ => Err(format!(
                "expected `watertight`, `uv-first` or `t-first`, got `{s}`"
            )),
        }
    }
}

/// Render settings that change the kernel (unlike features, not properties
/// of the scene): part of the stage kernel key.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Settings {
    /// Several samples per pixel: pixel jitter is compiled in.
    pub pixel_jitter: bool,
    /// Arbitrary output variables are written.
    pub aov: bool,
    /// One chunk holds every light sample of a pixel
    /// ([`super::tiles::TilePlan::chunks`]): the hit stage queues the light
    /// samples and traces their shadow rays from the hit it has in registers,
    /// instead of a shadow stage reading the hit records back.
    pub fused_shadows: bool,
    /// The stages write hit records, resolved materials and the queue as
    /// storage-buffer words over the texel images' memory
    /// (`vulkan::Context::stage_words`), not with texel stores.
    pub stage_words: bool,
    /// A stage invocation finds its pixel in its workgroup's block by its
    /// subgroup and lane (`vulkan::Context::lane_pixels`), not by its
    /// index in the workgroup, which lavapipe computes with divisions.
    pub lane_pixels: bool,
}

impl Settings {
    /// The settings of a render at `spp` samples per pixel, with or without
    /// AOVs, of a scene with `light_samples` light samples per pixel.
    pub fn new(spp: u32, aov: bool, light_samples: u32) -> Settings {
        Settings {
            // Pixel jitter is compiled in only when there is more than one
            // sample.
            pixel_jitter: spp > 1,
            aov,
            fused_shadows: super::tiles::one_chunk(light_samples),
            stage_words: false,
            lane_pixels: false,
        }
    }
}

/// What a stage is specialised to, and cached by (with its files' text):
/// the scene's features, the render settings and the user's kernel options.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct StageKernel {
    /// The kinds of primitive, light and shader the scene uses.
    pub features: Features,
    /// Sample count and outputs.
    pub settings: Settings,
    /// BVH or brute force, triangle test, shadow start, sampler...
    pub options: KernelOptions,
}

/// The WGSL `override` for each render setting, as in `shaders/render.wgsl`.
pub fn setting_values(s: &Settings) -> [(&'static str, bool); 5] {
    [
        ("PIXEL_JITTER", s.pixel_jitter),
        ("HAS_AOV", s.aov),
        ("FUSED_SHADOWS", s.fused_shadows),
        ("STAGE_WORDS", s.stage_words),
        ("LANE_PIXELS", s.lane_pixels),
    ]
}

/// The WGSL `override`s of the kernel options (besides the features' and
/// settings'), as in `shaders/render.wgsl`.
pub const OPTION_OVERRIDES: [&str; 5] = [
    "USE_BVH",
    "PACKET_TRAVERSAL",
    "TRIANGLE_TEST",
    "SHADOW_EPSILON",
    "SAMPLER",
];

/// The shade stage's WGSL `override` for each feature it depends on, as in
/// `shaders/shading/interface.wgsl` and `shaders/stages/shade.wgsl` (the
/// features [`super::shade::variant`] keeps): texture sampling, vertex
/// attributes, vertex colours, emission, checkers, planes and spheres, each
/// compiled in only for scenes that have it. Without colours a point's
/// colour is the constant (1, 1, 1, 1), so a built-in's `prepare` folds
/// away; without checkers the shade stage reads a hit's leaf shader from the
/// shader table instead of a resolved texel; without planes, spheres,
/// attributes and textures the hit records have no texel 4 to load
/// (`record_coords` in `shaders/stages/records.wgsl`); without occlusion
/// the environment's samples are not scaled.
pub fn shade_override_values(f: &Features) -> [(&'static str, bool); 8] {
    [
        ("penumbra_HAS_TEXTURES", f.textures),
        ("penumbra_HAS_ATTRIBUTES", f.attributes),
        ("penumbra_HAS_COLOURS", f.vertex_colours),
        ("penumbra_HAS_EMISSION", f.emission),
        ("penumbra_HAS_CHECKER", f.checker),
        ("penumbra_HAS_PLANES", f.planes),
        ("penumbra_HAS_SPHERES", f.spheres),
        ("penumbra_HAS_OCCLUSION", f.occlusion),
    ]
}

/// The shade stage's `override` (`shaders/stages/shade.wgsl`) for each
/// setting it depends on, named as in [`setting_values`] with `penumbra_`
/// before: it stores its colours as 64-bit words (`STAGE_WORDS`), and finds
/// its pixel by subgroup and lane (`LANE_PIXELS`).
pub fn shade_setting_values(s: &Settings) -> [(&'static str, bool); 2] {
    [
        ("penumbra_STAGE_WORDS", s.stage_words),
        ("penumbra_LANE_PIXELS", s.lane_pixels),
    ]
}

/// The WGSL `override` for each feature, as in `shaders/render.wgsl`.
pub fn override_values(f: &Features) -> [(&'static str, bool); 14] {
    [
        ("HAS_PLANES", f.planes),
        ("HAS_SPHERES", f.spheres),
        ("HAS_TRIANGLES", f.triangles),
        ("HAS_VERTEX_NORMALS", f.vertex_normals),
        ("HAS_DIRECTIONAL", f.directional_lights),
        ("HAS_POINT", f.point_lights),
        ("HAS_SPOT", f.spot_lights),
        ("HAS_CHECKER", f.checker),
        ("HAS_AREA_LIGHTS", f.area_lights),
        ("HAS_TEXTURES", f.textures),
        ("HAS_ATTRIBUTES", f.attributes),
        ("HAS_NORMAL_MAPS", f.normal_maps),
        ("HAS_ALPHA_TESTS", f.alpha_tests),
        ("HAS_SINGLE_SIDED", f.single_sided),
    ]
}

/// Explicit SPIR-V writer settings: SPIR-V 1.3 to match the Vulkan 1.1 we
/// request, and no debug info. Local arrays (a user's included) are clamped
/// into range everywhere (`index: Restrict`). The engine's buffers are not
/// checked by naga: every index is bounded by the counts in `Globals`, and a
/// user's file cannot name them (names starting with `penumbra_` are
/// refused, and so are declared resources). A user's values reach the
/// engine's resources only through the interface's texture functions, whose
/// texture index selects a record of the texel image of texture uses; so
/// the shade stage (`user_code`) checks its texel loads: one out of range
/// reads zero (`ReadZeroSkipWrite`; a zero record then samples nothing out
/// of range), one image-size query per fetch (docs/shaders.md has the cost).
/// The other stages' fetches stay unchecked (every BVH record index comes
/// from the encoder; the check would cost lavapipe an image-size call per
/// fetch). Buffers are unchecked in every stage: checks there also cost the
/// shade stage's compile a third more on every edit (bench_reload), and
/// `Restrict` clamped the engine's stores of rows outside an image band
/// into the band's last pixel.
fn spirv_options(user_code: bool) -> naga::back::spv::Options<'static> {
    use naga::proc::{BoundsCheckPolicies, BoundsCheckPolicy};
    let texels = if user_code {
        BoundsCheckPolicy::ReadZeroSkipWrite
    } else {
        BoundsCheckPolicy::Unchecked
    };
    naga::back::spv::Options {
        lang_version: (1, 3),
        flags: naga::back::spv::WriterFlags::empty(),
        bounds_check_policies: BoundsCheckPolicies {
            index: BoundsCheckPolicy::Restrict,
            buffer: BoundsCheckPolicy::Unchecked,
            image_load: texels,
            binding_array: BoundsCheckPolicy::Restrict,
        },
        ..Default::default()
    }
}

/// A WGSL module and its info, parsed and validated with every flag and
/// capability (the tests of `prune` and `spirv` start from one).
#[cfg(test)]
pub(crate) fn valid_module(src: &str) -> (naga::Module, naga::valid::ModuleInfo) {
    let module = naga::front::wgsl::parse_str(src).expect("WGSL");
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .expect("valid");
    (module, info)
}

/// The default shader directory of a source checkout, if it exists.
pub fn checkout_shader_dir() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    dir.is_dir().then_some(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn compile(src: &Assembled, f: &Features, k: &KernelOptions) -> Result<Vec<u32>, CompileError> {
        src.compile_frame(f, k)
    }

    /// The names of the `override`s `module` declares, sorted.
    fn override_names(module: &naga::Module) -> Vec<String> {
        let mut names: Vec<String> = module
            .overrides
            .iter()
            .filter_map(|(_, o)| o.name.clone())
            .collect();
        names.sort();
        names
    }

    /// The override tables (features, settings, kernel options) name
    /// exactly the `override`s the engine's WGSL declares.
    #[test]
    fn override_tables_match_the_wgsl() {
        let module = ShaderSource::Embedded.assemble().unwrap().parse().unwrap();
        let wgsl = override_names(&module);
        let mut table: Vec<String> = override_values(&Features::default())
            .iter()
            .map(|(n, _)| *n)
            .chain(setting_values(&Settings::default()).iter().map(|(n, _)| *n))
            .chain(OPTION_OVERRIDES)
            .map(String::from)
            .collect();
        table.sort();
        assert_eq!(wgsl, table);
    }

    /// The shade stage's override table names exactly the `override`s its
    /// WGSL declares; each is on for its own feature only, and where the
    /// engine has an override of the same feature (its name without
    /// `penumbra_`) that one is on for the same feature.
    #[test]
    fn shade_override_table_matches_the_wgsl() {
        let wgsl = override_names(&crate::render::shade::phong_module());
        let mut table: Vec<String> = shade_override_values(&Features::default())
            .iter()
            .map(|(n, _)| n.to_string())
            .chain(
                shade_setting_values(&Settings::default())
                    .iter()
                    .map(|(n, _)| n.to_string()),
            )
            .collect();
        table.sort();
        assert_eq!(wgsl, table);
        // Each setting's override is the engine's of that name, on for the
        // same setting: set one at a time and compare.
        let on = |names: &[(&str, bool)], prefix: &str| -> Vec<String> {
            names
                .iter()
                .filter(|(_, on)| *on)
                .map(|(n, _)| format!("{prefix}{n}"))
                .collect()
        };
        let one_at_a_time = [
            Settings {
                stage_words: true,
                ..Settings::default()
            },
            Settings {
                lane_pixels: true,
                ..Settings::default()
            },
        ];
        for s in one_at_a_time {
            let shade = on(&shade_setting_values(&s), "");
            assert_eq!(shade.len(), 1, "{s:?}");
            assert_eq!(shade, on(&setting_values(&s), "penumbra_"), "{s:?}");
        }
        // Every feature flag of the table maps to the engine's override of
        // the same feature: set one feature at a time and compare.
        let engine = |f: &Features| -> Vec<&str> {
            override_values(f)
                .into_iter()
                .filter(|(_, on)| *on)
                .map(|(n, _)| n)
                .collect()
        };
        for (i, (name, _)) in shade_override_values(&Features::default())
            .iter()
            .enumerate()
        {
            let mut f = Features::default();
            match i {
                0 => f.textures = true,
                1 => f.attributes = true,
                2 => f.vertex_colours = true,
                3 => f.emission = true,
                4 => f.checker = true,
                5 => f.planes = true,
                6 => f.spheres = true,
                _ => f.occlusion = true,
            }
            let on: Vec<&str> = shade_override_values(&f)
                .into_iter()
                .filter(|(_, on)| *on)
                .map(|(n, _)| n)
                .collect();
            assert_eq!(on, [*name]);
            if !matches!(
                *name,
                "penumbra_HAS_COLOURS" | "penumbra_HAS_EMISSION" | "penumbra_HAS_OCCLUSION"
            ) {
                assert_eq!(engine(&f), [name.strip_prefix("penumbra_").unwrap()]);
            }
            // shade::variant keeps the feature, so pipelines of scenes that
            // differ in it have different keys.
            assert_ne!(
                crate::render::shade::variant(&f),
                crate::render::shade::variant(&Features::default()),
                "{name}"
            );
        }
    }

    #[test]
    fn every_feature_set_compiles() {
        /// SPIR-V's `Int64` capability.
        const INT64: u32 = 11;
        let src = ShaderSource::Embedded.assemble().unwrap();
        let all = Features {
            planes: true,
            spheres: true,
            triangles: true,
            vertex_normals: true,
            directional_lights: true,
            point_lights: true,
            spot_lights: true,
            checker: true,
            area_lights: true,
            textures: true,
            attributes: true,
            vertex_colours: true,
            emission: true,
            normal_maps: true,
            alpha_tests: true,
            single_sided: true,
            occlusion: true,
        };
        for accel in [Accel::Bvh, Accel::BruteForce] {
            for triangle_test in [
                TriangleTest::UvFirst,
                TriangleTest::TFirst,
                TriangleTest::Watertight,
            ] {
                let kernel = KernelOptions {
                    accel,
                    triangle_test,
                    shadow_offset: ShadowOffset::Fixed(1e-4),
                    ..Default::default()
                };
                let words = compile(&src, &all, &kernel).unwrap();
                assert_eq!(words[0], 0x0723_0203, "SPIR-V magic");
                // No driver may fuse the kernels' float arithmetic
                // (render::spirv says why).
                let key = StageKernel {
                    features: all,
                    settings: Settings::default(),
                    options: kernel,
                };
                for stage in super::super::stages::Stage::FRAME {
                    let words = src.compile_entry(&key, stage.entry_point()).unwrap();
                    assert_eq!(
                        super::super::spirv::contractible_results(&words),
                        0,
                        "{stage:?}"
                    );
                    // Without stage words no stage uses 64-bit integers,
                    // so a device without shaderInt64 runs them all.
                    assert!(
                        !super::super::spirv::capabilities(&words).contains(&INT64),
                        "{stage:?}"
                    );
                }
                // With them the hit stage stores its records as 64-bit words.
                let words_key = StageKernel {
                    settings: Settings {
                        stage_words: true,
                        ..Settings::default()
                    },
                    ..key
                };
                let hit = src
                    .compile_entry(&words_key, super::super::stages::Stage::Hit.entry_point())
                    .unwrap();
                assert!(super::super::spirv::capabilities(&hit).contains(&INT64));
                assert_eq!(words[1], 0x0001_0300, "SPIR-V 1.3");
                compile(&src, &Features::default(), &kernel).unwrap();
            }
        }
    }

    /// A shader that declares a binding as something other than what the
    /// renderer binds there fails to compile, naming the file, the variable
    /// and both kinds (the driver would otherwise see the mismatch).
    #[test]
    fn mismatched_bindings_are_compile_errors() {
        let src = ShaderSource::Embedded.assemble().unwrap();
        let kernel = KernelOptions::default();
        let f = Features::default();
        // (text edits, words the error must contain)
        type Case<'a> = (&'a [(&'a str, &'a str)], [&'a str; 5]);
        let cases: [Case; 3] = [
            (
                // The BVH's records and the lights swapped.
                &[
                    ("@binding(9) var bvh_nodes", "@binding(5) var bvh_nodes"),
                    (
                        "@binding(5) var<storage, read> lights",
                        "@binding(9) var<storage, read> lights",
                    ),
                ],
                [
                    ".wgsl:",
                    "@binding(",
                    "declared as a",
                    "texel image",
                    "read-only storage buffer",
                ],
            ),
            (
                &[(
                    "var<storage, read> lights",
                    "var<storage, read_write> lights",
                )],
                [
                    "lights.wgsl:",
                    "`lights`",
                    "@binding(5)",
                    "var<storage, read_write>",
                    "var<storage, read>",
                ],
            ),
            (
                &[("@binding(3) var triangles", "@binding(40) var triangles")],
                [
                    "triangle.wgsl:",
                    "`triangles`",
                    "@binding(40)",
                    "texel image",
                    "binds nothing",
                ],
            ),
        ];
        for (edits, words) in cases {
            let mut bad = src.clone();
            for (from, to) in edits {
                assert!(bad.text.contains(from), "{from}");
                bad.text = bad.text.replace(from, to);
            }
            let err = compile(&bad, &f, &kernel).unwrap_err().to_string();
            for w in words {
                assert!(err.contains(w), "{w:?} missing from: {err}");
            }
        }
    }

    #[test]
    fn text_specialisation_compiles_and_matches_the_override_kernel_size() {
        let src = ShaderSource::Embedded.assemble().unwrap();
        let f = Features {
            triangles: true,
            directional_lights: true,
            ..Default::default()
        };
        let overrides = compile(&src, &f, &KernelOptions::default()).unwrap();
        let text = KernelOptions {
            text_specialise: true,
            ..Default::default()
        };
        let text = compile(&src, &f, &text).unwrap();
        assert_eq!(text[0], 0x0723_0203);
        // naga keeps constant-condition branches either way: the dead code is
        // left to the driver's compiler (docs/bench.md measures the result).
        let ratio = text.len() as f64 / overrides.len() as f64;
        assert!(
            (0.8..1.2).contains(&ratio),
            "{} vs {}",
            text.len(),
            overrides.len()
        );
    }

    #[test]
    fn errors_point_at_the_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let src = ShaderSource::Embedded.assemble().unwrap();
        for (name, start, count) in &src.files {
            let rel = name.trim_start_matches("shaders/");
            let body: Vec<&str> = src
                .text
                .lines()
                .skip(*start as usize - 1)
                .take(*count as usize)
                .collect();
            let mut body = body.join("\n");
            if rel == "lights.wgsl" {
                body = body.replacen("let dist = sqrt(dist2);", "let dist = sqrt(dist2) +;", 1);
            }
            let path = dir.path().join(rel);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, body).unwrap();
        }
        let broken = ShaderSource::Directory(dir.path().to_path_buf())
            .assemble()
            .unwrap();
        let err = compile(&broken, &Features::default(), &KernelOptions::default()).unwrap_err();
        let want_line = include_str!("../../shaders/lights.wgsl")
            .lines()
            .position(|l| l.contains("let dist = sqrt(dist2);"))
            .unwrap()
            + 1;
        assert!(err.location.contains("lights.wgsl"), "{err}");
        assert!(err.location.contains(&format!(":{want_line}:")), "{err}");
        assert!(
            err.message.contains("sqrt(dist2) +;") && err.message.contains('^'),
            "{err}"
        );
    }
}
