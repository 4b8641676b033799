//! Pass `trace` (`trace.wgsl`): one compute thread per ray, ray buffer in, hit
//! buffer out, in chunks that fit one binding. Mirrors `dirt_cpu::trace`.
//!
//! Each ray has a budget of loop iterations (`work.wgsl`): lavapipe silently
//! ends all loops of an invocation after 65535 iterations. A ray that spends
//! its budget comes back marked [`UNFINISHED`] and is traced again here by the
//! CPU reference, whose hits and statistics are the GPU's bit for bit; the
//! number of such rays is reported.

use crate::fill_primitives::grid;
use crate::{
    Gpu, GpuAds, GpuError, TraceParams, check_binding, read_back, storage_init, uniform_init,
};
use dirt_core::Traversal;
use dirt_math::dda::hiz_levels;
use dirt_math::{Hit, Ray, RayStats};

/// Rays per dispatch: small enough for any binding limit and to keep each
/// submission short.
const CHUNK: usize = 1 << 18;

/// The primitive id the shader writes for a ray that ran out of its work budget.
pub const UNFINISHED: u32 = 0xffff_fffe;

/// Closest hits and per-ray statistics of `rays`. Rays that fail
/// [`Ray::validate`] (non-finite values, a zero direction, a bad range) miss,
/// as in `dirt_cpu::trace` and `dirt_cpu::brute_force::trace`; so does a
/// valid ray whose hit parameter `t` would overflow `f32`.
pub fn trace(
    gpu: &Gpu,
    ads: &GpuAds,
    rays: &[Ray],
    traversal: Traversal,
) -> Result<(Vec<Hit>, Vec<RayStats>), GpuError> {
    let t = trace_report(gpu, ads, rays, traversal)?;
    Ok((t.hits, t.stats))
}

/// What [`trace_report`] returns.
#[derive(Clone, Debug, Default)]
pub struct Traced {
    pub hits: Vec<Hit>,
    pub stats: Vec<RayStats>,
    /// Rays the GPU left unfinished (work budget spent) that the CPU reference traced.
    pub cpu_finished: usize,
}

/// [`trace`], also saying how many rays the CPU reference had to finish.
pub fn trace_report(
    gpu: &Gpu,
    ads: &GpuAds,
    rays: &[Ray],
    traversal: Traversal,
) -> Result<Traced, GpuError> {
    let mut out = Traced {
        hits: Vec::with_capacity(rays.len()),
        stats: Vec::with_capacity(rays.len()),
        cpu_finished: 0,
    };
    for chunk in rays.chunks(CHUNK) {
        let (h, s) = trace_chunk(gpu, ads, chunk, traversal)?;
        out.hits.extend(h);
        out.stats.extend(s);
    }
    let unfinished: Vec<usize> = (0..rays.len())
        .filter(|&i| out.hits[i].prim == UNFINISHED)
        .collect();
    if !unfinished.is_empty() {
        let cpu = match ads.cpu.get() {
            Some(c) => c,
            None => {
                let built = dirt_cpu::Ads::build(&ads.triangles, &ads.params)?;
                ads.cpu.get_or_init(|| built)
            }
        };
        let again: Vec<Ray> = unfinished.iter().map(|&i| rays[i]).collect();
        let (h, s) = dirt_cpu::trace_with_stats(cpu, &ads.triangles, &again, traversal);
        for (k, &i) in unfinished.iter().enumerate() {
            out.hits[i] = h[k];
            out.stats[i] = s[k];
        }
        out.cpu_finished = unfinished.len();
    }
    Ok(out)
}

fn trace_chunk(
    gpu: &Gpu,
    ads: &GpuAds,
    rays: &[Ray],
    traversal: Traversal,
) -> Result<(Vec<Hit>, Vec<RayStats>), GpuError> {
    let n = rays.len() as u64;
    check_binding(gpu, "rays", n * 32)?;
    let ray_buf = storage_init(
        gpu,
        "rays",
        bytemuck::cast_slice(rays),
        wgpu::BufferUsages::empty(),
    );
    let hit_buf = storage_init(
        gpu,
        "hits",
        &vec![0u8; (n * 16) as usize],
        wgpu::BufferUsages::COPY_SRC,
    );
    let stat_buf = storage_init(
        gpu,
        "stats",
        &vec![0u8; (n * 16) as usize],
        wgpu::BufferUsages::COPY_SRC,
    );
    let tiles = ads.params.tiles();
    let params = TraceParams {
        n_rays: n as u32,
        n_views: ads.views.views.len() as u32,
        n_slots: ads.views.slots() as u32,
        tiles,
        buckets: ads.params.buckets,
        levels: hiz_levels(tiles),
        traversal: match traversal {
            Traversal::Linear => 0,
            Traversal::HiZ => 1,
        },
        ..Default::default()
    };
    let u = uniform_init(gpu, "trace params", bytemuck::bytes_of(&params));
    let p = &gpu.pipelines.trace;
    let bind = crate::bind_buffers(
        gpu,
        "trace",
        &p.get_bind_group_layout(0),
        &[
            (0, &ray_buf),
            (1, &hit_buf),
            (2, &ads.tris),
            (3, &ads.views_uniform),
            (4, &u),
            (5, &ads.hiz),
            (6, &ads.offsets),
            (7, &ads.ids),
            (8, &stat_buf),
        ],
    );
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let (x, y) = grid(gpu, n.div_ceil(64));
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(p);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
    gpu.queue.submit([enc.finish()]);
    gpu.wait()?;
    let hits = bytemuck::pod_collect_to_vec::<u8, Hit>(&read_back(gpu, &hit_buf, 0, n * 16)?);
    let stats =
        bytemuck::pod_collect_to_vec::<u8, RayStats>(&read_back(gpu, &stat_buf, 0, n * 16)?);
    Ok((hits[..n as usize].to_vec(), stats[..n as usize].to_vec()))
}
