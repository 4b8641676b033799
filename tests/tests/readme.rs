//! The README's "Using the crates" example, run as written: the code between
//! the markers below must stand in README.md line for line.

use std::error::Error;

fn cpu_example() -> Result<(), Box<dyn Error>> {
    // README BEGIN
    use dirt_core::Tracer;
    use dirt_cpu::{DirtCpu, brute_force::Brute};
    use dirt_math::{Ray, Vec3};

    let scene = dirt_scene::open("cornell")?; // built-in name or glTF/OBJ path
    let rays = vec![Ray::new(
        Vec3::new(0.0, 1.0, 1.9),
        Vec3::new(0.0, 0.0, -1.0),
        0.0,
        f32::INFINITY,
    )];

    // The cost model chooses the parameters for frames of 100 000 rays at the first
    // build, and the faster traversal (None; Some(Traversal::HiZ) fixes it), timed on a
    // sample; DirtCpu::new(AdsParams { .. }, traversal) fixes every parameter instead.
    let mut dirt = DirtCpu::auto(None, 100_000);
    // Where every ray traced in a frame starts at one point (camera rays), the next build
    // places the views there and later builds move them with it; .with_origin(eye) says
    // so from the first build, .with_sample(&rays) hands over rays like a frame's.
    dirt.build(&scene.triangles)?; // rebuild every frame for a moving scene
    let hits = dirt.trace(&rays)?;
    let truth = Brute::new(&scene.triangles).trace(&rays)?;
    assert_eq!(hits[0].bits(), truth[0].bits()); // Hit { prim, t, u, v }; hit.is_hit()
    // README END
    assert!(
        hits[0].is_hit(),
        "the example's ray hits the floor of cornell"
    );
    Ok(())
}

#[test]
fn the_readme_example_runs() {
    cpu_example().expect("README example");
}

/// The README's embedding example: an application's device, queue, vertex,
/// index, ray and hit buffers and encoder.
#[allow(clippy::too_many_arguments)]
fn gpu_example(
    device: &dirt_gpu::wgpu::Device,
    queue: &dirt_gpu::wgpu::Queue,
    vertex_buffer: &dirt_gpu::wgpu::Buffer,
    index_buffer: &dirt_gpu::wgpu::Buffer,
    triangle_count: u32,
    ray_buffer: &dirt_gpu::wgpu::Buffer,
    hit_buffer: &dirt_gpu::wgpu::Buffer,
    rays: &[dirt_math::Ray],
) -> Result<(), Box<dyn Error>> {
    use dirt_core::Traversal;
    let count = rays.len() as u32; // rays in ray_buffer
    // README GPU BEGIN
    use dirt_core::gather::{IndexFormat, MeshLayout};
    use dirt_gpu::{DirtGpu, Gpu, GpuMesh, GpuOptions, wgpu}; // dirt's wgpu: the same version as yours
    let gpu = Gpu::from_device(device, queue, &GpuOptions::default())?;
    let mut dirt = DirtGpu::new(&gpu, dirt_core::AdsParams::default(), Traversal::HiZ);
    // Each frame: the application's own buffers, with STORAGE usage. Here 12-byte vertices
    // (the position at byte 0) and u32 indices; any stride, offset, u16 and a transform work.
    let mesh = GpuMesh {
        vertices: vertex_buffer,
        indices: Some(index_buffer),
        layout: MeshLayout::indexed(12, 0, IndexFormat::U32, triangle_count),
    };
    // rays: STORAGE, 32 bytes a ray (dirt_math::Ray); hits: STORAGE, 16 bytes a hit (dirt_math::Hit)
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    dirt.encode_build(&mut encoder, &[mesh])?; // the structure, built from those buffers
    dirt.encode_trace(&mut encoder, ray_buffer, hit_buffer, None, count)?;
    queue.submit([encoder.finish()]); // build and trace run from here; dirt never waits
    // README GPU END
    Ok(())
}

#[test]
fn the_readme_gpu_example_runs() {
    use dirt_gpu::wgpu::{self, util::DeviceExt};
    if dirt_gpu::testing::exact_gpu("the_readme_gpu_example_runs").is_none() {
        return;
    }
    let (device, queue) = pollster::block_on(dirt_gpu::Gpu::open_device()).expect("a device");
    let rays = [dirt_math::Ray::new(
        dirt_math::Vec3::new(0.0, 1.0, 1.9),
        dirt_math::Vec3::new(0.0, 0.0, -1.0),
        0.0,
        f32::INFINITY,
    )];
    let scene = dirt_scene::open("cornell").expect("cornell");
    let init = |contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents,
            usage,
        })
    };
    let vertex_buffer = init(
        bytemuck::cast_slice(&scene.triangles),
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX,
    );
    let indices: Vec<u32> = (0..scene.triangles.len() as u32 * 3).collect();
    let index_buffer = init(
        bytemuck::cast_slice(&indices),
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDEX,
    );
    let ray_buffer = init(bytemuck::cast_slice(&rays), wgpu::BufferUsages::STORAGE);
    let hit_buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: 16,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    gpu_example(
        &device,
        &queue,
        &vertex_buffer,
        &index_buffer,
        scene.triangles.len() as u32,
        &ray_buffer,
        &hit_buffer,
        &rays,
    )
    .expect("README GPU example");
    let hit: dirt_math::Hit =
        bytemuck::pod_read_unaligned(&dirt_tests::read_buffer(&device, &queue, &hit_buffer));
    let truth = dirt_cpu::brute_force::trace(&scene.triangles, &rays);
    assert!(hit.is_hit(), "{hit:?}");
    assert_eq!(hit.bits(), truth[0].bits());
}

/// The text without any whitespace, so rustfmt's layout here and the README's
/// compare equal.
fn squeeze(s: &str) -> String {
    s.split_whitespace().collect()
}

#[test]
fn the_readme_shows_this_example() {
    let me = include_str!("readme.rs");
    let start = me.find("// README BEGIN").expect("begin marker") + "// README BEGIN".len();
    let end = me.find("    // README END").expect("end marker");
    let example = squeeze(&me[start..end]);
    assert!(
        squeeze(include_str!("../../README.md")).contains(&example),
        "README.md's `Using the crates` example differs from tests/tests/readme.rs"
    );
    let start = me.find("// README GPU BEGIN").expect("begin marker") + "// README GPU BEGIN".len();
    let end = me.find("    // README GPU END").expect("end marker");
    assert!(
        squeeze(include_str!("../../README.md")).contains(&squeeze(&me[start..end])),
        "README.md's embedding example differs from tests/tests/readme.rs"
    );
}
