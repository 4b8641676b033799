//! Shader compilation. On Vulkan adapters with passthrough shaders (lavapipe
//! and real GPUs alike) the WGSL is compiled here with naga to SPIR-V, every
//! float arithmetic result is decorated `NoContraction`, and the module is
//! handed to the driver as is. Without that decoration a driver may fuse
//! `a*b + c` or rewrite float expressions algebraically: on lavapipe it
//! turned `(p - q) + (pe - qe)` of the exact two-product difference into
//! something else, and GPU and CPU disagreed in the last bit. Bind group
//! layouts are derived from naga's reflection of each entry point.
#![allow(unsafe_code)]

use crate::GpuError;
use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};
use std::borrow::Cow;
use std::collections::BTreeMap;

/// A stage's shader, validated by naga; pipelines are made from it with [`Stage::prepare`].
#[derive(Debug)]
pub(crate) struct Stage {
    name: &'static str,
    naga: naga::Module,
    info: ModuleInfo,
    /// The module wgpu compiled from WGSL, when not on the NoContraction path.
    wgsl: Option<wgpu::ShaderModule>,
}

/// What a pipeline is made of: its layout and, per entry point asked for, a module.
#[derive(Debug)]
pub(crate) struct Prepared {
    pub layout: wgpu::PipelineLayout,
    pub modules: Vec<wgpu::ShaderModule>,
}

/// SPIR-V opcodes of float arithmetic whose results get `NoContraction`.
const FLOAT_ARITHMETIC: [u32; 14] = [
    127, // OpFNegate
    129, // OpFAdd
    131, // OpFSub
    133, // OpFMul
    136, // OpFDiv
    140, // OpFRem
    141, // OpFMod
    142, // OpVectorTimesScalar
    143, // OpMatrixTimesScalar
    144, // OpVectorTimesMatrix
    145, // OpMatrixTimesVector
    146, // OpMatrixTimesMatrix
    147, // OpOuterProduct
    148, // OpDot
];
const OP_DECORATE: u32 = 71;
const NO_CONTRACTION: u32 = 42;

/// Adds `OpDecorate %id NoContraction` for the result of every float
/// arithmetic instruction. Returns how many were added.
pub fn decorate_no_contraction(words: &mut Vec<u32>) -> Result<usize, String> {
    if words.len() < 5 || words[0] != 0x0723_0203 {
        return Err("not a SPIR-V module".into());
    }
    let mut ids = Vec::new();
    let mut insert_at = None;
    let mut first_type = None;
    let mut at = 5;
    while at < words.len() {
        let op = words[at] & 0xffff;
        let len = (words[at] >> 16) as usize;
        if len == 0 || at + len > words.len() {
            return Err(format!("malformed instruction at word {at}"));
        }
        // Annotations: OpDecorate .. OpGroupMemberDecorate, OpDecorateId, OpDecorateString, OpMemberDecorateString.
        if insert_at.is_none() && ((71..=75).contains(&op) || op == 332 || op == 5632 || op == 5633)
        {
            insert_at = Some(at);
        }
        if first_type.is_none() && (19..=39).contains(&op) {
            first_type = Some(at);
        }
        if FLOAT_ARITHMETIC.contains(&op) && len >= 3 {
            ids.push(words[at + 2]);
        }
        at += len;
    }
    let Some(pos) = insert_at.or(first_type) else {
        return Err("no place for decorations".into());
    };
    let mut deco = Vec::with_capacity(ids.len() * 3);
    for id in &ids {
        deco.extend_from_slice(&[(3 << 16) | OP_DECORATE, *id, NO_CONTRACTION]);
    }
    words.splice(pos..pos, deco);
    Ok(ids.len())
}

fn parse(
    stage: &'static str,
    chunks: dirt_shaders::Chunks,
) -> Result<(naga::Module, ModuleInfo, String), GpuError> {
    let composed = dirt_shaders::compose_chunked(stage, chunks).map_err(|e| GpuError::Shader {
        stage,
        message: e.to_string(),
    })?;
    let module = naga::front::wgsl::parse_str(&composed.text).map_err(|e| GpuError::Shader {
        stage,
        message: e.emit_to_string(&composed.text),
    })?;
    let info = Validator::new(ValidationFlags::all(), Capabilities::empty())
        .validate(&module)
        .map_err(|e| GpuError::Shader {
            stage,
            message: e.emit_to_string(&composed.text),
        })?;
    Ok((module, info, composed.text))
}

/// Parses and validates a stage. With `passthrough`, pipelines get NoContraction
/// SPIR-V (see the module docs); else wgpu compiles the WGSL (no bits promised).
pub(crate) fn compile(
    device: &wgpu::Device,
    stage: &'static str,
    passthrough: bool,
    chunks: dirt_shaders::Chunks,
) -> Result<Stage, GpuError> {
    let (module, info, text) = parse(stage, chunks)?;
    let wgsl = (!passthrough).then(|| {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(stage),
            source: wgpu::ShaderSource::Wgsl(text.into()),
        })
    });
    Ok(Stage {
        name: stage,
        naga: module,
        info,
        wgsl,
    })
}

impl Stage {
    /// Every bound global the entry points use, visible to the stages that use it.
    fn bindings(
        &self,
        entries: &[&str],
    ) -> Result<BTreeMap<(u32, u32), wgpu::BindGroupLayoutEntry>, GpuError> {
        let mut bindings: BTreeMap<(u32, u32), wgpu::BindGroupLayoutEntry> = BTreeMap::new();
        for name in entries {
            let Some((idx, ep)) = self
                .naga
                .entry_points
                .iter()
                .enumerate()
                .find(|(_, e)| e.name == *name)
            else {
                return Err(GpuError::Shader {
                    stage: self.name,
                    message: format!("no entry point `{name}`"),
                });
            };
            let visibility = match ep.stage {
                naga::ShaderStage::Vertex => wgpu::ShaderStages::VERTEX,
                naga::ShaderStage::Fragment => wgpu::ShaderStages::FRAGMENT,
                _ => wgpu::ShaderStages::COMPUTE,
            };
            let fi = self.info.get_entry_point(idx);
            for (h, var) in self.naga.global_variables.iter() {
                let Some(rb) = &var.binding else { continue };
                if fi[h].is_empty() {
                    continue;
                }
                let ty = match var.space {
                    naga::AddressSpace::Uniform => wgpu::BufferBindingType::Uniform,
                    naga::AddressSpace::Storage { access } => wgpu::BufferBindingType::Storage {
                        read_only: !access.contains(naga::StorageAccess::STORE),
                    },
                    other => {
                        return Err(GpuError::Shader {
                            stage: self.name,
                            message: format!(
                                "binding {}:{} in {other:?} is not supported",
                                rb.group, rb.binding
                            ),
                        });
                    }
                };
                let e =
                    bindings
                        .entry((rb.group, rb.binding))
                        .or_insert(wgpu::BindGroupLayoutEntry {
                            binding: rb.binding,
                            visibility: wgpu::ShaderStages::empty(),
                            ty: wgpu::BindingType::Buffer {
                                ty,
                                has_dynamic_offset: false,
                                min_binding_size: None,
                            },
                            count: None,
                        });
                e.visibility |= visibility;
            }
        }
        Ok(bindings)
    }

    /// The layout of a pipeline made of `entries` (from naga's reflection), and
    /// one module per entry point (SPIR-V path) or the shared WGSL module.
    pub(crate) fn prepare(
        &self,
        device: &wgpu::Device,
        entries: &[&str],
    ) -> Result<Prepared, GpuError> {
        let bindings = self.bindings(entries)?;
        let groups = bindings.keys().map(|(g, _)| *g + 1).max().unwrap_or(0);
        let layouts: Vec<wgpu::BindGroupLayout> = (0..groups)
            .map(|g| {
                let entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
                    .iter()
                    .filter(|((gg, _), _)| *gg == g)
                    .map(|(_, e)| *e)
                    .collect();
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: None,
                    entries: &entries,
                })
            })
            .collect();
        let refs: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(Some).collect();
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(self.name),
            bind_group_layouts: &refs,
            immediate_size: 0,
        });
        if let Some(m) = &self.wgsl {
            return Ok(Prepared {
                layout,
                modules: vec![m.clone()],
            });
        }
        // wgpu's Vulkan backend numbers the descriptors of a bind group
        // densely in binding order; the SPIR-V must use the same numbers.
        let mut binding_map = naga::back::spv::BindingMap::default();
        for g in 0..groups {
            for (rank, ((_, b), _)) in bindings.iter().filter(|((gg, _), _)| *gg == g).enumerate() {
                binding_map.insert(
                    naga::ResourceBinding {
                        group: g,
                        binding: *b,
                    },
                    naga::back::spv::BindingInfo {
                        descriptor_set: g,
                        binding: rank as u32,
                        binding_array_size: None,
                    },
                );
            }
        }
        let options = naga::back::spv::Options {
            lang_version: (1, 3),
            // wgpu flips y with a negative viewport height, so no coordinate adjustment here.
            flags: naga::back::spv::WriterFlags::LABEL_VARYINGS
                | naga::back::spv::WriterFlags::FORCE_POINT_SIZE,
            bounds_check_policies: naga::proc::BoundsCheckPolicies {
                index: naga::proc::BoundsCheckPolicy::Restrict,
                buffer: naga::proc::BoundsCheckPolicy::Restrict,
                image_load: naga::proc::BoundsCheckPolicy::Restrict,
                binding_array: naga::proc::BoundsCheckPolicy::Unchecked,
            },
            fake_missing_bindings: false,
            binding_map,
            ..Default::default()
        };
        let mut modules = Vec::new();
        for name in entries {
            let Some(ep) = self.naga.entry_points.iter().find(|e| e.name == *name) else {
                return Err(GpuError::Shader {
                    stage: self.name,
                    message: format!("no entry point `{name}`"),
                });
            };
            let pipeline = naga::back::spv::PipelineOptions {
                shader_stage: ep.stage,
                entry_point: ep.name.clone(),
            };
            let mut words =
                naga::back::spv::write_vec(&self.naga, &self.info, &options, Some(&pipeline))
                    .map_err(|e| GpuError::Shader {
                        stage: self.name,
                        message: e.to_string(),
                    })?;
            decorate_no_contraction(&mut words).map_err(|message| GpuError::Shader {
                stage: self.name,
                message,
            })?;
            let entry = [wgpu::PassthroughShaderEntryPoint {
                name: Cow::Owned(ep.name.clone()),
                workgroup_size: (
                    ep.workgroup_size[0],
                    ep.workgroup_size[1],
                    ep.workgroup_size[2],
                ),
            }];
            // SAFETY: the SPIR-V is naga's own output for a module naga validated,
            // with bounds checks on every index and buffer access and bindings
            // numbered as wgpu numbers them; the only change is added
            // NoContraction decorations, which restrict the driver and add no behaviour.
            modules.push(unsafe {
                device.create_shader_module_passthrough(wgpu::ShaderModuleDescriptorPassthrough {
                    label: Some(self.name),
                    entry_points: Cow::Borrowed(&entry),
                    spirv: Some(Cow::Owned(words)),
                    ..Default::default()
                })
            });
        }
        Ok(Prepared { layout, modules })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decorates_every_float_op() {
        let (module, info, _) = parse("trace", dirt_shaders::Chunks::ONE).expect("trace parses");
        let mut words =
            naga::back::spv::write_vec(&module, &info, &naga::back::spv::Options::default(), None)
                .expect("spv");
        let before = words.len();
        let n = decorate_no_contraction(&mut words).expect("decorates");
        assert!(n > 100, "only {n} float ops in trace");
        assert_eq!(words.len(), before + 3 * n);
        // The result still parses as SPIR-V with the decorations in the annotation section.
        let m = naga::front::spv::parse_u8_slice(bytemuck::cast_slice(&words), &Default::default());
        assert!(m.is_ok(), "{m:?}");
    }

    #[test]
    fn rejects_garbage() {
        assert!(decorate_no_contraction(&mut vec![1, 2, 3]).is_err());
    }
}
