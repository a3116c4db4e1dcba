//! The transport tables in a fragment shader, with the host side written out as an engine
//! writes it (docs/integration.md, "The host side"): an explicit bind group layout (the `.ntt`
//! words as a read-only storage buffer, its index as a uniform, each with its minimum binding
//! size), a render pipeline drawing one triangle over a 64 × 48 R32Float target, and the
//! picture read back. Each pixel is a point on the lit face of a 16-mfp slab (sun 60° from
//! the zenith), the view cosine rising down the image and the azimuth across it; its value is
//! order 1 plus T of every group (`nephele_transport_all`), which must follow the runtime as
//! the compute kernel does (tests/tables.rs).

mod common;
use common::gpu;
use nephele_runtime::transport::{SlabPoint, TransportTables};
use std::num::NonZeroU64;

const SHIPPED: &[u8] = include_bytes!("../../runtime/tables/mie10um/transport.ntt");
const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;
const THICKNESS: f32 = 16.0;
const MU_L: f32 = 0.5;

/// The renderer's shader, after `nephele_wgsl::tables_module(0, 0)`.
const SHADER: &str = r#"
@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle over the whole target.
    let x = f32((i << 1u) & 2u);
    let y = f32(i & 2u);
    return vec4<f32>(2.0 * x - 1.0, 1.0 - 2.0 * y, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    // The pixel's point: the lit face (d = 0), views going up (mu_V = p.y / 48), azimuth
    // pi p.x / 64 (radians).
    let at = nephele_slab_point(16.0, 0.5, 0.0, p.y / 48.0, NEPHELE_PI * p.x / 64.0);
    let groups = nephele_transport_all(at);
    var radiance_per_e = nephele_order1(at);
    for (var g = 0u; g < nephele_ntt_index.groups; g++) {
        radiance_per_e += groups[g];
    }
    return vec4<f32>(radiance_per_e, 0.0, 0.0, 1.0);
}
"#;

/// The picture the fragment shader draws, row by row.
fn draw(ntt: &nephele_wgsl::NttGpu) -> Vec<f32> {
    use wgpu::util::DeviceExt;
    let device = &gpu().device;
    let queue = &gpu().queue;
    // The two buffers: what `nephele export-gpu` writes as tables.bin and index.bin.
    let words = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("nephele tables"),
        contents: bytemuck::cast_slice(&ntt.words),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    });
    let index = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("nephele tables index"),
        contents: bytemuck::cast_slice(&ntt.index),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    });
    let entry = |binding, ty, bytes: usize| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: NonZeroU64::new(bytes as u64),
        },
        count: None,
    };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("nephele tables"),
        entries: &[
            entry(
                0,
                wgpu::BufferBindingType::Storage { read_only: true },
                4 * ntt.words.len(),
            ),
            entry(
                1,
                wgpu::BufferBindingType::Uniform,
                4 * nephele_wgsl::NTT_INDEX_WORDS,
            ),
        ],
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("nephele tables"),
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: words.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: index.as_entire_binding(),
            },
        ],
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("slab picture"),
        source: wgpu::ShaderSource::Wgsl(
            format!("{}\n{SHADER}", nephele_wgsl::tables_module(0, 0)).into(),
        ),
    });
    let format = wgpu::TextureFormat::R32Float;
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("slab picture"),
        layout: Some(
            &device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            }),
        ),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    let size = wgpu::Extent3d {
        width: WIDTH,
        height: HEIGHT,
        depth_or_array_layers: 1,
    };
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("picture"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    // 64 pixels of 4 bytes: a row is the 256 bytes a copy's rows must be a multiple of.
    let row_bytes = 4 * WIDTH;
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: (row_bytes * HEIGHT) as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let view = target.create_view(&Default::default());
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("slab picture"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(0..3, 0..1);
    }
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: &target,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row_bytes),
                rows_per_image: Some(HEIGHT),
            },
        },
        size,
    );
    queue.submit([encoder.finish()]);
    readback.map_async(wgpu::MapMode::Read, .., |r| r.expect("map the picture"));
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("the draw finishes");
    let bytes = readback.get_mapped_range(..).expect("the mapped picture");
    bytemuck::cast_slice(&bytes).to_vec()
}

/// Every pixel within the tables test's agreement of the runtime's value at the same point:
/// the median distance below 1e-6, the largest below 1e-3 (tests/tables.rs finds up to 9.7e-4
/// between two f32 evaluations of one group).
#[test]
fn a_fragment_shader_draws_the_tables_as_the_runtime_evaluates_them() {
    let tables = TransportTables::from_bytes(SHIPPED).unwrap();
    let ntt = nephele_wgsl::ntt_for_gpu(SHIPPED).unwrap();
    let picture = draw(&ntt);
    let mut groups = vec![0.0f32; tables.groups()];
    let mut d: Vec<f64> = (0..HEIGHT)
        .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
        .zip(&picture)
        .map(|((x, y), &got)| {
            let at = SlabPoint {
                thickness: THICKNESS,
                mu_l: MU_L,
                depth: 0.0,
                mu_v: (y as f32 + 0.5) / HEIGHT as f32,
                psi_v: std::f32::consts::PI * (x as f32 + 0.5) / WIDTH as f32,
            };
            tables.transport_all(&at, &mut groups);
            let want = tables.order1(&at) + groups.iter().sum::<f32>();
            assert!(want > 0.0, "the runtime's light at pixel ({x}, {y})");
            ((got - want) / want).abs() as f64
        })
        .collect();
    d.sort_by(f64::total_cmp);
    let (median, max) = (d[d.len() / 2], d[d.len() - 1]);
    println!(
        "fragment shader, {WIDTH} × {HEIGHT} pixels on {} (tables {} bytes, index {}): order 1 \
         + T of every group within {median:.1e} of the runtime (median), {max:.1e} at most",
        gpu().adapter,
        4 * ntt.words.len(),
        4 * ntt.index.len()
    );
    assert!(
        median <= 1e-6 && max <= 1e-3,
        "median {median:e}, max {max:e}"
    );
}
