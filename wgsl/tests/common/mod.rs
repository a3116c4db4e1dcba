//! A Vulkan device (any wgpu adapter: Mesa's lavapipe on the CPU in CI) and one-dispatch
//! compute runs, shared by the tests of the WGSL port.

use std::sync::OnceLock;
use wgpu::util::DeviceExt;

/// The device every test of a binary shares.
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// Adapter name, backend and driver, for the reports.
    #[allow(dead_code)] // not every test binary reports it
    pub adapter: String,
}

pub fn gpu() -> &'static Gpu {
    static GPU: OnceLock<Gpu> = OnceLock::new();
    GPU.get_or_init(|| pollster::block_on(open()))
}

async fn open() -> Gpu {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = instance
        .request_adapter(&wgpu::RequestAdapterOptions::default())
        .await
        .expect(
            "no GPU adapter: install a Vulkan driver (Debian: apt-get install mesa-vulkan-drivers, \
             which gives lavapipe on the CPU)",
        );
    let info = adapter.get_info();
    let (device, queue) = adapter
        .request_device(&wgpu::DeviceDescriptor {
            label: Some("nephele-wgsl tests"),
            required_features: wgpu::Features::empty(),
            required_limits: wgpu::Limits::downlevel_defaults(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        })
        .await
        .expect("a device on the adapter");
    Gpu {
        device,
        queue,
        adapter: format!("{} ({:?}, {})", info.name, info.backend, info.driver),
    }
}

/// The compute pipeline of `source`'s entry point `main`.
#[allow(dead_code)] // not every test binary computes
pub fn pipeline(label: &str, source: &str) -> wgpu::ComputePipeline {
    let g = gpu();
    let module = g.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    g.device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        })
}

/// A buffer the kernel reads at a binding of group 0.
pub struct Input<'a> {
    pub binding: u32,
    pub bytes: &'a [u8],
    /// `true`: a uniform; `false`: a read-only storage buffer.
    pub uniform: bool,
}

/// Runs `pipeline` once over `invocations` (workgroups of 64) with `inputs` bound in group 0
/// and a storage buffer of `out_bytes` at `out_binding`, and reads that buffer back.
pub fn dispatch(
    pipeline: &wgpu::ComputePipeline,
    inputs: &[Input],
    (out_binding, out_bytes): (u32, u64),
    invocations: u32,
) -> Vec<u8> {
    let g = gpu();
    let buffers: Vec<(u32, wgpu::Buffer)> = inputs
        .iter()
        .map(|i| {
            let usage = if i.uniform {
                wgpu::BufferUsages::UNIFORM
            } else {
                wgpu::BufferUsages::STORAGE
            };
            let buffer = g
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: None,
                    contents: i.bytes,
                    usage,
                });
            (i.binding, buffer)
        })
        .collect();
    let output = g.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("outputs"),
        size: out_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = g.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("staging"),
        size: out_bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    entries.push(wgpu::BindGroupEntry {
        binding: out_binding,
        resource: output.as_entire_binding(),
    });
    let bind = g.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = g.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(invocations.div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &staging, 0, out_bytes);
    g.queue.submit([encoder.finish()]);
    staging.map_async(wgpu::MapMode::Read, .., |r| r.expect("map the outputs"));
    g.device
        .poll(wgpu::PollType::wait_indefinitely())
        .expect("the kernel finishes");
    let view = staging.get_mapped_range(..).expect("mapped outputs");
    view.to_vec()
}

/// Runs `pipeline` with the test kernels' layout: the job (4 u32) as a uniform at binding 0,
/// `data` (f32) at binding 1, the output (`out_bytes`) at binding 2 and, given one, a `.ntt`
/// laid out for the GPU at bindings 3 (words) and 4 (index).
#[allow(dead_code)] // not every test binary reads a .ntt
pub fn run_kernel(
    pipeline: &wgpu::ComputePipeline,
    job: [u32; 4],
    data: &[f32],
    ntt: Option<&nephele_wgsl::NttGpu>,
    out_bytes: u64,
    invocations: u32,
) -> Vec<u8> {
    let mut inputs = vec![
        Input {
            binding: 0,
            bytes: bytemuck::cast_slice(&job),
            uniform: true,
        },
        Input {
            binding: 1,
            bytes: bytemuck::cast_slice(data),
            uniform: false,
        },
    ];
    if let Some(ntt) = ntt {
        inputs.push(Input {
            binding: 3,
            bytes: bytemuck::cast_slice(&ntt.words),
            uniform: false,
        });
        inputs.push(Input {
            binding: 4,
            bytes: bytemuck::cast_slice(&ntt.index),
            uniform: true,
        });
    }
    dispatch(pipeline, &inputs, (2, out_bytes), invocations)
}
