//! An application's frame loop with dirt-gpu, on a deforming glTF model.
//!
//! ```text
//! cargo run --release -p dirt-gpu --example deforming -- [model.glb] [frames] [size] [out-dir]
//! ```
//!
//! The application opens its own device, uploads the glTF's vertex and index
//! buffers as they are in the file (interleaved or not, u16 or u32 indices,
//! each node's world transform), and every frame:
//! 1. deforms the vertices on the host and writes them with `Queue::write_buffer`;
//! 2. records the build (`GpuAds::encode_build`) and the trace of a camera's
//!    primary rays (`TraceResources::encode_trace`) into its own encoder;
//! 3. submits once and reads the hits back, as it would read any buffer;
//! 4. writes the frame as a PNG.
//!
//! dirt submits and waits for nothing itself. A frame whose lists outgrow
//! the ids (the first, usually: their size is a guess until a build has
//! counted them) says so in every hit, and the application records it again.
//! `tests/tests/examples.rs` runs this and checks every frame against the CPU.

use dirt_core::gather::{self, Affine, IndexFormat, MeshLayout};
use dirt_core::{AdsParams, Traversal};
use dirt_gpu::trace::STRUCTURE_FULL;
use dirt_gpu::{BuildFeedback, Gpu, GpuAds, GpuMesh, GpuOptions, TraceResources, wgpu};
use dirt_math::{Aabb, Hit, Ray, Triangle, Vec3};
use std::error::Error;
use std::path::{Path, PathBuf};
use wgpu::util::DeviceExt;

/// The model when none is given: Debian's assimp-testmodels has it.
pub const DEFAULT_MODEL: &str =
    "/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";

#[derive(Debug)]
pub struct Options {
    pub model: PathBuf,
    pub frames: u32,
    /// Image width and height in pixels (one primary ray each).
    pub size: u32,
    /// Where `frame-000.png`, … go; `None` writes no image.
    pub out: Option<PathBuf>,
    pub params: AdsParams,
}

/// One frame: the triangles as the GPU built them (gathered the same way on
/// the CPU), the rays, and the hits the GPU returned.
#[derive(Debug)]
pub struct FrameResult {
    pub triangles: Vec<Triangle>,
    pub rays: Vec<Ray>,
    pub hits: Vec<Hit>,
    /// Times the frame was recorded again because its lists outgrew the ids.
    pub rerecorded: u32,
}

#[derive(Debug)]
pub struct Run {
    pub adapter: String,
    /// The device runs the exact path (the CPU's bits are promised).
    pub exact: bool,
    pub frames: Vec<FrameResult>,
    pub feedback: BuildFeedback,
}

/// One glTF primitive as the application keeps it: the bytes of its buffer
/// views (a host copy, to deform) and their GPU buffers.
struct Primitive {
    vertex_bytes: Vec<u8>,
    index_bytes: Option<Vec<u8>>,
    vertex_count: usize,
    layout: MeshLayout,
    vertices: wgpu::Buffer,
    indices: Option<wgpu::Buffer>,
}

/// Bytes padded to whole words (storage buffers are read in words).
fn padded(mut b: Vec<u8>) -> Vec<u8> {
    b.resize(b.len().max(16).div_ceil(4) * 4, 0);
    b
}

fn mul(a: &[[f32; 4]; 4], b: &[[f32; 4]; 4]) -> [[f32; 4]; 4] {
    // Column-major: m[col][row].
    let mut m = [[0.0; 4]; 4];
    for (c, col) in m.iter_mut().enumerate() {
        for (r, v) in col.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[k][r] * b[c][k]).sum();
        }
    }
    m
}

fn affine(m: &[[f32; 4]; 4]) -> Affine {
    [0, 1, 2].map(|r| [m[0][r], m[1][r], m[2][r], m[3][r]])
}

/// The primitives of the default scene with their nodes' world transforms.
fn load(path: &Path, gpu: &Gpu) -> Result<Vec<Primitive>, Box<dyn Error>> {
    let (doc, buffers, _) = gltf::import(path)?;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or("the glTF has no scene")?;
    let mut out = Vec::new();
    let mut stack: Vec<(gltf::Node, [[f32; 4]; 4])> = scene
        .nodes()
        .map(|n| {
            let m = n.transform().matrix();
            (n, m)
        })
        .collect();
    while let Some((node, world)) = stack.pop() {
        for child in node.children() {
            let m = mul(&world, &child.transform().matrix());
            stack.push((child, m));
        }
        let Some(mesh) = node.mesh() else { continue };
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
                continue;
            };
            let view = pos
                .view()
                .ok_or("sparse positions are not supported here")?;
            let data = &buffers[view.buffer().index()].0;
            let stride = view.stride().unwrap_or(12);
            // The view from the vertex holding the first position on.
            let skip = pos.offset() - pos.offset() % stride;
            let start = view.offset() + skip;
            let vertex_bytes = padded(data[start..view.offset() + view.length()].to_vec());
            let vertex_count = pos.count();
            let (index_bytes, format, first, triangles) = match prim.indices() {
                Some(ix) => {
                    let iv = ix.view().ok_or("sparse indices are not supported here")?;
                    let bytes =
                        &buffers[iv.buffer().index()].0[iv.offset()..iv.offset() + iv.length()];
                    let (bytes, format, size) = match ix.data_type() {
                        gltf::accessor::DataType::U16 => (bytes.to_vec(), IndexFormat::U16, 2),
                        gltf::accessor::DataType::U32 => (bytes.to_vec(), IndexFormat::U32, 4),
                        // u8 indices: widened to u16, as a WebGPU application must.
                        _ => (
                            bytes
                                .iter()
                                .flat_map(|&b| (b as u16).to_le_bytes())
                                .collect(),
                            IndexFormat::U16,
                            1,
                        ),
                    };
                    let first = (ix.offset() / size) as u32;
                    (
                        Some(padded(bytes)),
                        Some(format),
                        first,
                        (ix.count() / 3) as u32,
                    )
                }
                None => (None, None, 0, (vertex_count / 3) as u32),
            };
            let layout = MeshLayout {
                vertex_stride: stride as u32,
                position_offset: (pos.offset() % stride) as u32,
                index_format: format,
                first_index: first,
                triangles,
                transform: Some(affine(&world)),
            };
            let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
            let vertices = gpu
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("vertices"),
                    contents: &vertex_bytes,
                    usage: usage | wgpu::BufferUsages::VERTEX,
                });
            let indices = index_bytes.as_ref().map(|b| {
                gpu.device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("indices"),
                        contents: b,
                        usage: usage | wgpu::BufferUsages::INDEX,
                    })
            });
            out.push(Primitive {
                vertex_bytes,
                index_bytes,
                vertex_count,
                layout,
                vertices,
                indices,
            });
        }
    }
    Ok(out)
}

/// A primitive's vertices at time `t`: a wave along its own x, by its own size.
fn deform(p: &Primitive, t: f32) -> Vec<u8> {
    let mut bytes = p.vertex_bytes.clone();
    let (stride, off) = (
        p.layout.vertex_stride as usize,
        p.layout.position_offset as usize,
    );
    let read = |b: &[u8], at: usize| f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
    let mut lo = f32::INFINITY;
    let mut hi = f32::NEG_INFINITY;
    for i in 0..p.vertex_count {
        let y = read(&bytes, i * stride + off + 4);
        lo = lo.min(y);
        hi = hi.max(y);
    }
    let size = (hi - lo).max(1e-6);
    for i in 0..p.vertex_count {
        let at = i * stride + off;
        let (x, y) = (read(&bytes, at), read(&bytes, at + 4));
        let x = x + 0.08 * size * (t + 6.0 * (y - lo) / size).sin();
        bytes[at..at + 4].copy_from_slice(&x.to_le_bytes());
    }
    bytes
}

/// A pinhole camera in front of `b`, one ray per pixel, rows top to bottom.
fn camera(b: &Aabb, size: u32) -> Vec<Ray> {
    let c = b.center();
    let r = b.extent().length() * 0.5;
    let eye = c + Vec3::new(0.6, 0.5, 1.0).normalize() * (2.2 * r);
    let fwd = (c - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    (0..size * size)
        .map(|k| {
            let (x, y) = (k % size, k / size);
            let sx = (x as f32 + 0.5) / size as f32 * 2.0 - 1.0;
            let sy = 1.0 - (y as f32 + 0.5) / size as f32 * 2.0;
            let d = (fwd + right * (0.6 * sx) + up * (0.6 * sy)).normalize();
            Ray::new(eye, d, 0.0, f32::INFINITY)
        })
        .collect()
}

fn write_png(
    path: &Path,
    size: u32,
    rays: &[Ray],
    hits: &[Hit],
    tris: &[Triangle],
) -> Result<(), Box<dyn Error>> {
    let mut rgb = Vec::with_capacity(rays.len() * 3);
    for (ray, h) in rays.iter().zip(hits) {
        let px = match tris.get(h.prim as usize) {
            Some(t) if h.is_hit() => {
                let n = (t.vertex(1) - t.vertex(0))
                    .cross(t.vertex(2) - t.vertex(0))
                    .normalize_or_zero();
                let s = 0.15 + 0.85 * n.dot(Vec3::from(ray.dir)).abs();
                [(230.0 * s) as u8, (200.0 * s) as u8, (160.0 * s) as u8]
            }
            _ => [40, 50, 70],
        };
        rgb.extend_from_slice(&px);
    }
    image::save_buffer(path, &rgb, size, size, image::ColorType::Rgb8)?;
    Ok(())
}

pub fn run(opts: &Options) -> Result<Run, Box<dyn Error>> {
    let (device, queue) = pollster::block_on(Gpu::open_device())?;
    let gpu = Gpu::from_device(&device, &queue, &GpuOptions::default())?;
    let prims = load(&opts.model, &gpu)?;
    if prims.is_empty() {
        return Err(format!("{} has no triangle primitive", opts.model.display()).into());
    }
    // The frame-0 triangles place the camera; it stays put while the model moves.
    let rest: Vec<Triangle> = prims
        .iter()
        .map(|p| gather::gather(&p.vertex_bytes, p.index_bytes.as_deref(), &p.layout))
        .collect::<Result<Vec<_>, _>>()?
        .concat();
    let rays = camera(&Aabb::of_triangles(&rest), opts.size);
    let n = rays.len() as u64;
    let ray_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("rays"),
        contents: bytemuck::cast_slice(&rays),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let hit_buf = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hits"),
        size: n * 16,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hits read-back"),
        size: n * 16,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut ads = GpuAds::frame(&gpu, &opts.params, 1 << 20)?;
    let mut trace = TraceResources::new(&gpu);
    if let Some(dir) = &opts.out {
        std::fs::create_dir_all(dir)?;
    }
    let mut frames = Vec::new();
    for f in 0..opts.frames {
        let t = f as f32 * 0.8;
        let mut host = Vec::new();
        for p in &prims {
            let bytes = deform(p, t);
            queue.write_buffer(&p.vertices, 0, &bytes);
            host.push(gather::gather(&bytes, p.index_bytes.as_deref(), &p.layout)?);
        }
        let meshes: Vec<GpuMesh<'_>> = prims
            .iter()
            .map(|p| GpuMesh {
                vertices: &p.vertices,
                indices: p.indices.as_ref(),
                layout: p.layout,
            })
            .collect();
        let mut rerecorded = 0;
        let hits = loop {
            let mut enc = device.create_command_encoder(&Default::default());
            ads.encode_build(&gpu, &mut enc, &meshes)?;
            trace.encode_trace(
                &gpu,
                &mut enc,
                &ads,
                &ray_buf,
                &hit_buf,
                None,
                n as u32,
                Traversal::HiZ,
            )?;
            enc.copy_buffer_to_buffer(&hit_buf, 0, &staging, 0, n * 16);
            queue.submit([enc.finish()]);
            let (tx, rx) = std::sync::mpsc::channel();
            staging.map_async(wgpu::MapMode::Read, .., move |r| {
                let _ = tx.send(r);
            });
            device.poll(wgpu::PollType::wait_indefinitely())?;
            rx.recv()??;
            let hits: Vec<Hit> = bytemuck::pod_collect_to_vec(&staging.get_mapped_range(..)?);
            staging.unmap();
            // An incomplete structure says so in every hit: record the frame again
            // (the build has grown its ids from the count it just made).
            if hits.iter().any(|h| h.prim == STRUCTURE_FULL) && rerecorded < 3 {
                rerecorded += 1;
                continue;
            }
            break hits;
        };
        let triangles = host.concat();
        if let Some(dir) = &opts.out {
            write_png(
                &dir.join(format!("frame-{f:03}.png")),
                opts.size,
                &rays,
                &hits,
                &triangles,
            )?;
        }
        frames.push(FrameResult {
            triangles,
            rays: rays.clone(),
            hits,
            rerecorded,
        });
    }
    Ok(Run {
        adapter: gpu.describe(),
        exact: gpu.exact,
        frames,
        feedback: ads.feedback().unwrap_or_default(),
    })
}

#[allow(dead_code)]
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |k: usize| args.get(k).map(String::as_str);
    let parse = |k: usize, default: u32| arg(k).map_or(Ok(default), str::parse::<u32>);
    let (frames, size) = match (parse(1, 8), parse(2, 256)) {
        (Ok(f), Ok(s)) if f > 0 && s > 0 => (f, s),
        _ => {
            eprintln!("usage: deforming [model.glb] [frames > 0] [size > 0] [out-dir]");
            std::process::exit(2);
        }
    };
    let opts = Options {
        model: PathBuf::from(arg(0).unwrap_or(DEFAULT_MODEL)),
        frames,
        size,
        out: Some(PathBuf::from(arg(3).unwrap_or("target/deforming"))),
        params: AdsParams::default(),
    };
    match run(&opts) {
        Ok(r) => {
            let hit = r
                .frames
                .iter()
                .map(|f| f.hits.iter().filter(|h| h.is_hit()).count())
                .sum::<usize>();
            println!(
                "{} frames of {} triangles on {}: {hit} hits; builds recorded {}, re-recorded after an overflow {}, ids grown {} times to {} entries; images in {}",
                r.frames.len(),
                r.frames.first().map_or(0, |f| f.triangles.len()),
                r.adapter,
                r.feedback.recorded,
                r.frames.iter().map(|f| f.rerecorded).sum::<u32>(),
                r.feedback.grown,
                r.feedback.capacity,
                opts.out.as_deref().unwrap_or(Path::new("-")).display(),
            );
        }
        Err(e) => {
            eprintln!("deforming: {e}");
            std::process::exit(1);
        }
    }
}
