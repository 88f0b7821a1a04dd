//! One frame: surfaces, then the fat borders of every border vertex, into the targets.

use super::*;
use super::{pipelines::*, readback::*};

impl Renderer {
    /// Renders `geometry` ([`GpuMeshes`] or [`ResidentGeometry`]) for `view` and reads the
    /// image (and depth, if asked) back.
    pub fn render<'a>(
        &mut self,
        geometry: impl Into<Geometry<'a>>,
        view: &View,
        opts: &RenderOptions,
    ) -> Result<Frame, RenderError> {
        let meshes = geometry.into();
        self.last = RenderStats::default();
        let (w, h) = (view.width, view.height);
        let max = self.gpu.max_texture_side();
        if w == 0 || h == 0 {
            return Err(RenderError::BadSize {
                width: w,
                height: h,
                reason: "zero-sized".into(),
            });
        }
        if w > max || h > max {
            return Err(RenderError::BadSize {
                width: w,
                height: h,
                reason: format!("this adapter's largest texture side is {max}"),
            });
        }
        if opts.msaa != 1 && opts.msaa != 4 {
            return Err(RenderError::BadSampleCount(opts.msaa));
        }
        let scope = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
        let oom = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let globals = self.globals(view, opts);
        let bg = opts.background.map(|c| c as f64 / 255.0);
        let clear = wgpu::Color {
            r: bg[0],
            g: bg[1],
            b: bg[2],
            a: 1.0,
        };
        let color = self.draw(
            meshes,
            &globals,
            opts,
            Target::Color { samples: opts.msaa },
            w,
            h,
            clear,
        )?;
        let depth = if opts.depth {
            let no = wgpu::Color {
                r: NO_DEPTH as f64,
                g: 0.0,
                b: 0.0,
                a: 0.0,
            };
            let bits: Vec<u32> = self.draw(meshes, &globals, opts, Target::Depth, w, h, no)?;
            Some(
                bits.into_iter()
                    .map(|b| {
                        if b == NO_DEPTH {
                            f32::INFINITY
                        } else {
                            f32::from_bits(b)
                        }
                    })
                    .collect(),
            )
        } else {
            None
        };
        let ids = if opts.ids {
            let none = wgpu::Color {
                r: 0.0,
                g: 0.0,
                b: 0.0,
                a: 0.0,
            };
            Some(self.draw(meshes, &globals, opts, Target::Ids, w, h, none)?)
        } else {
            None
        };
        if let Some(e) = pollster::block_on(oom.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        Ok(Frame {
            width: w,
            height: h,
            color,
            depth,
            ids,
        })
    }

    /// Records the draws of `meshes` into `pass` (surfaces, then the fat borders of
    /// `variant`, then with `edges` the edge lines the globals' mode selects) with `pipes`
    /// and the globals bound by `bind`: the one encoding of a frame, shared by the offscreen
    /// [`Renderer::render`] and a caller's pass ([`crate::embed`]).
    pub(crate) fn encode_into(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        meshes: Geometry<'_>,
        pipes: &Pipelines,
        bind: &wgpu::BindGroup,
        variant: FatBorders,
        edges: Option<&EdgePipelines>,
    ) {
        pass.set_bind_group(0, bind, &[]);
        match meshes {
            Geometry::Uploaded(m) => m.encode(pass, pipes, &self.patterns, variant, edges),
            Geometry::Resident(r) => r.encode(
                pass,
                pipes,
                &self.patterns,
                variant,
                edges,
                self.gpu.indirect,
            ),
        }
    }

    /// The bind group of a uniform buffer of [`Globals`] (group 0 of every pipeline).
    pub(crate) fn globals_bind_group(&self, uniform: &wgpu::Buffer) -> wgpu::BindGroup {
        self.gpu
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("globals"),
                layout: &self.bind_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                }],
            })
    }

    pub(crate) fn globals(&self, view: &View, opts: &RenderOptions) -> Globals {
        let forward = view.forward();
        let right = forward.cross(view.up).try_normalize().unwrap_or(DVec3::X);
        let up = right.cross(forward);
        // A key light from above-left of the viewer.
        let light = (-forward * 0.8 + up * 0.55 - right * 0.35).normalize();
        let f4 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
        let c = opts.surface_color;
        Globals {
            view_proj: view.view_proj_f32().to_cols_array_2d(),
            // w: 1 perspective, 0 orthographic (the shader's `viewer()`).
            eye: {
                let v = view.eye.as_vec3();
                [v.x, v.y, v.z, view.viewer().w as f32]
            },
            forward: f4(forward),
            light: f4(light),
            color: [c[0], c[1], c[2], 1.0],
            mode: [
                match opts.shading {
                    Shading::Lit => 0,
                    Shading::Flat => 1,
                    Shading::Ids => 2,
                },
                fat_border::template(opts.fat_borders).len() as u32,
                opts.sections.len() as u32,
                opts.edges.bits() as u32,
            ],
            sections: opts.sections.gpu(),
        }
    }

    /// One pass into a fresh target; returns the unpadded texels of the (resolved) colour
    /// target, as bytes or 32-bit words.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn draw<T: bytemuck::Pod>(
        &mut self,
        meshes: Geometry<'_>,
        globals: &Globals,
        opts: &RenderOptions,
        target: Target,
        w: u32,
        h: u32,
        clear: wgpu::Color,
    ) -> Result<Vec<T>, RenderError> {
        let cut = !opts.sections.is_empty();
        self.pipelines_for(target, cut);
        if opts.edges != Edges::Off {
            self.edge_pipelines(target);
        }
        if self.targets.get(&target).is_none_or(|t| t.size != (w, h)) {
            let t = Targets::new(&self.gpu, &self.bind_layout, target, w, h);
            self.targets.insert(target, t);
        }
        let device = &self.gpu.device;
        // Built just above.
        let pipes = if cut {
            &self.cut_pipelines[&target]
        } else {
            &self.pipelines[&target]
        };
        let edges = (opts.edges != Edges::Off)
            .then(|| self.edge_pipes.get(&target))
            .flatten();
        let targets = &self.targets[&target];
        self.gpu
            .queue
            .write_buffer(&targets.uniform, 0, bytemuck::bytes_of(globals));
        self.last.uniform_bytes += size_of::<Globals>() as u64;
        let (resolved_view, msaa_view, depth_view, bind) = (
            &targets.resolved_view,
            &targets.msaa_view,
            &targets.depth_view,
            &targets.bind,
        );
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let (view, resolve_target) = match msaa_view {
                Some(v) => (v, Some(resolved_view)),
                None => (resolved_view, None),
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("scene"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.encode_into(&mut pass, meshes, pipes, bind, opts.fat_borders, edges);
        }
        read_texture(&self.gpu, encoder, targets, &mut self.last.gpu_wait)
    }
}
