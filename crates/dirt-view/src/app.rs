//! The window's event loop: input moves the camera or the animation, each
//! redraw adds one sample pass and presents the mean.

use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

use dirt_render::Renderer;
use dirt_render::gpu::GpuRenderer;
use dirt_scene::AnimatedScene;
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

use crate::accum::Accumulator;
use crate::orbit::{ORBIT_PER_KEY, Orbit};
use crate::present::{Device, Presenter};
use crate::{ViewError, ViewOptions, ViewTracer};

/// Which drag is under way.
#[derive(Clone, Copy, Debug, Default)]
struct Buttons {
    left: bool,
    right: bool,
    middle: bool,
}

/// The animation clock: seconds into the clip, advancing while playing.
#[derive(Clone, Copy, Debug)]
struct Clock {
    base: f32,
    since: Option<Instant>,
}

impl Clock {
    fn now(&self) -> f32 {
        self.base + self.since.map_or(0.0, |s| s.elapsed().as_secs_f32())
    }
    fn playing(&self) -> bool {
        self.since.is_some()
    }
    fn toggle(&mut self) {
        match self.since.take() {
            Some(s) => self.base += s.elapsed().as_secs_f32(),
            None => self.since = Some(Instant::now()),
        }
    }
}

pub struct App<'g> {
    options: ViewOptions,
    scene: AnimatedScene,
    tracer: ViewTracer<'g>,
    /// Shading on the GPU (DIRT on the GPU, a still scene, not declined):
    /// its renderer, made for the first sample and kept while the image
    /// keeps its size; the sums are presented where they lie.
    shade_on_gpu: bool,
    shaded: Option<GpuRenderer<'g>>,
    /// Samples per pixel in the GPU renderer's sums, and when they started.
    gpu_samples: u32,
    /// The scene was posed since the GPU renderer last restarted: its
    /// triangle and light tables are rewritten, not just the camera.
    posed: bool,
    gpu_start: Instant,
    device: &'g Device,
    window: Option<Arc<Window>>,
    presenter: Option<Presenter>,
    orbit: Orbit,
    accum: Accumulator,
    clock: Clock,
    /// The camera moved since the last pass: restart the accumulation.
    moved: bool,
    buttons: Buttons,
    modifiers: ModifiersState,
    cursor: Option<PhysicalPosition<f64>>,
    frames: u64,
    /// Rays per second of the last pass, for the title.
    mrays_per_s: f64,
    rays: u64,
    error: Option<ViewError>,
}

impl std::fmt::Debug for App<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("App")
            .field("scene", &self.scene.scene.name)
            .field("tracer", &self.tracer.name())
            .field("frames", &self.frames)
            .field("samples", &self.samples())
            .finish_non_exhaustive()
    }
}

impl<'g> App<'g> {
    pub fn new(
        options: ViewOptions,
        scene: AnimatedScene,
        tracer: ViewTracer<'g>,
        device: &'g Device,
    ) -> Result<Self, ViewError> {
        let shade_on_gpu = matches!(tracer, ViewTracer::Gpu(_)) && !options.host_shading;
        if shade_on_gpu {
            eprintln!(
                "dirt view: shaded on the GPU, the image presented where it lies (no read-back)"
            );
        }
        let (w, h) = options.internal_size(options.width, options.height);
        let orbit = crate::start_camera(&options, &scene.scene, w as f32 / h as f32)?;
        let clock = Clock {
            base: 0.0,
            since: (options.play && scene.is_animated()).then(Instant::now),
        };
        if scene.is_animated() {
            eprintln!(
                "dirt view: the scene moves ({:.2} s a loop); {} (space toggles)",
                scene.duration(),
                if clock.playing() { "playing" } else { "paused" }
            );
        }
        Ok(Self {
            options,
            scene,
            tracer,
            shade_on_gpu,
            shaded: None,
            gpu_samples: 0,
            posed: false,
            gpu_start: Instant::now(),
            device,
            window: None,
            presenter: None,
            orbit,
            accum: Accumulator::new(w, h),
            clock,
            moved: false,
            buttons: Buttons::default(),
            modifiers: ModifiersState::default(),
            cursor: None,
            frames: 0,
            mrays_per_s: 0.0,
            rays: 0,
            error: None,
        })
    }

    /// What the event loop ended with.
    pub fn finish(mut self) -> Result<(), ViewError> {
        if let Some(e) = self.error {
            return Err(e);
        }
        // Shaded on the GPU: its counters, read once, say whether every hit was one.
        if let Some(g) = self.shaded.as_mut() {
            g.counters()?;
        }
        Ok(())
    }

    /// Samples per pixel in the image shown.
    fn samples(&self) -> u32 {
        if self.shade_on_gpu {
            self.gpu_samples
        } else {
            self.accum.samples
        }
    }

    fn converged(&self) -> bool {
        self.options
            .max_samples
            .is_some_and(|m| self.samples() >= m)
    }

    /// One more sample on the GPU, added to the sums there; the renderer is
    /// made for the first sample and pointed at the camera of each restart.
    /// The counters are read back once, when the image is done.
    fn gpu_sample(&mut self) -> Result<(), ViewError> {
        let ViewTracer::Gpu(t) = &self.tracer else {
            return Err(ViewError::Internal(
                "GPU shading without DIRT on the GPU".into(),
            ));
        };
        let (w, h) = (self.accum.width, self.accum.height);
        if self.gpu_samples == 0 {
            let settings = self.options.settings(w, h);
            let renderer = Renderer::new(&self.scene.scene, self.orbit.camera()?, settings)?;
            GpuRenderer::reuse(&mut self.shaded, t.gpu(), &renderer, self.posed)?;
            self.posed = false;
            self.gpu_start = Instant::now();
        }
        let ads = t.built_ads()?;
        let Some(g) = self.shaded.as_mut() else {
            return Err(ViewError::Internal("no GPU renderer".into()));
        };
        g.add_sample(ads, t.traversal, self.gpu_samples)?;
        self.gpu_samples += 1;
        if self
            .options
            .max_samples
            .is_some_and(|m| self.gpu_samples >= m)
        {
            // Done: the one read-back says how many rays, and that every hit was one.
            let c = g.counters()?;
            self.rays = c.rays_total();
            let secs = self.gpu_start.elapsed().as_secs_f64();
            self.mrays_per_s = self.rays as f64 / secs.max(1e-9) / 1e6;
        }
        Ok(())
    }

    /// Whether another redraw would change the image.
    fn busy(&self) -> bool {
        !self.converged() || self.moved || (self.clock.playing() && self.scene.is_animated())
    }

    /// One displayed frame: pose (when playing), one more sample pass (until
    /// `max_samples`), present, report.
    fn frame(&mut self, event_loop: &ActiveEventLoop) -> Result<(), ViewError> {
        if self.clock.playing() && self.scene.is_animated() {
            let d = self.scene.duration();
            let t = if d > 0.0 { self.clock.now() % d } else { 0.0 };
            self.scene
                .pose(t)
                .map_err(|source| ViewError::Pose { time: t, source })?;
            // The triangles moved: DIRT is rebuilt (same parameters), the image restarts.
            self.tracer.as_tracer().build(&self.scene.scene.triangles)?;
            self.accum.reset();
            self.gpu_samples = 0;
            self.posed = true;
        }
        if self.moved {
            self.accum.reset();
            self.gpu_samples = 0;
            self.moved = false;
        }
        if self.shade_on_gpu {
            if !self.converged() {
                self.gpu_sample()?;
            }
            if let (Some(p), Some(g)) = (self.presenter.as_mut(), self.shaded.as_ref()) {
                let (w, h) = (self.accum.width, self.accum.height);
                p.draw_sums(g.sums(), w, h, self.gpu_samples, self.options.exposure)?;
            }
        } else {
            if !self.converged() {
                let settings = self.options.settings(self.accum.width, self.accum.height);
                let renderer = Renderer::new(&self.scene.scene, self.orbit.camera()?, settings)?;
                let start = Instant::now();
                let pass = renderer.render_sample(self.tracer.as_tracer(), self.accum.samples)?;
                let secs = start.elapsed().as_secs_f64();
                self.accum.add(&pass.radiance)?;
                self.rays = pass.rays;
                self.mrays_per_s = pass.rays as f64 / secs.max(1e-9) / 1e6;
            }
            let rgba = self.accum.rgba8(self.options.exposure);
            if let Some(p) = self.presenter.as_mut() {
                p.draw(&rgba, self.accum.width, self.accum.height)?;
            }
        }
        self.frames += 1;
        self.report();
        if self.options.frames.is_some_and(|n| self.frames >= n) {
            event_loop.exit();
        }
        Ok(())
    }

    /// The title bar and the stdout line.
    fn report(&self) {
        let anim = if self.scene.is_animated() {
            format!(
                " | {} t={:.2}s",
                if self.clock.playing() {
                    "playing"
                } else {
                    "paused"
                },
                self.scene.time()
            )
        } else {
            String::new()
        };
        if let Some(w) = &self.window {
            w.set_title(&format!(
                "dirt view: {} | {} spp | {:.2} Mrays/s | {}x{} | {}{}{anim}",
                self.scene.scene.name,
                self.samples(),
                self.mrays_per_s,
                self.accum.width,
                self.accum.height,
                self.tracer.name(),
                if self.shade_on_gpu {
                    ", shaded on the GPU"
                } else {
                    ""
                },
            ));
        }
        let every = self.options.print_every;
        if every > 0 && self.frames.is_multiple_of(every) {
            let (e, t) = (self.orbit.eye, self.orbit.target);
            let mut out = std::io::stdout().lock();
            // A closed pipe only loses the report, not the window.
            let _ = writeln!(
                out,
                "frame {} samples {} rays {} mrays_per_s {:.3} time {} camera eye={},{},{} target={},{},{} fov={}",
                self.frames,
                self.samples(),
                self.rays,
                self.mrays_per_s,
                self.scene.time(),
                e.x,
                e.y,
                e.z,
                t.x,
                t.y,
                t.z,
                self.orbit.fov
            );
            let _ = out.flush();
        }
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, key: &Key) {
        let before = self.orbit;
        match key {
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Character(c) if c.eq_ignore_ascii_case("q") => event_loop.exit(),
            Key::Character(c) if c.eq_ignore_ascii_case("r") => self.orbit.reset(),
            Key::Named(NamedKey::Space) => {
                if self.scene.is_animated() {
                    self.clock.toggle();
                    // Paused: the pose stays, samples accumulate on it.
                    self.moved = true;
                } else {
                    eprintln!("dirt view: the scene does not move (nothing to play)");
                }
            }
            Key::Named(NamedKey::ArrowLeft) => self.orbit.rotate(-ORBIT_PER_KEY, 0.0),
            Key::Named(NamedKey::ArrowRight) => self.orbit.rotate(ORBIT_PER_KEY, 0.0),
            Key::Named(NamedKey::ArrowUp) => self.orbit.rotate(0.0, ORBIT_PER_KEY),
            Key::Named(NamedKey::ArrowDown) => self.orbit.rotate(0.0, -ORBIT_PER_KEY),
            Key::Character(c) if c == "+" || c == "=" => self.orbit.zoom(1.0),
            Key::Character(c) if c == "-" => self.orbit.zoom(-1.0),
            _ => {}
        }
        if self.orbit != before {
            self.moved = true;
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: ViewError) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }

    fn open_window(&mut self, event_loop: &ActiveEventLoop) -> Result<(), ViewError> {
        let attrs = Window::default_attributes()
            .with_title(format!("dirt view: {}", self.scene.scene.name))
            .with_inner_size(PhysicalSize::new(self.options.width, self.options.height));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| ViewError::NoDisplay(e.to_string()))?,
        );
        self.presenter = Some(Presenter::new(self.device, window.clone())?);
        let size = window.inner_size();
        self.window = Some(window);
        self.resized(size);
        Ok(())
    }

    fn resized(&mut self, size: PhysicalSize<u32>) {
        if size.width == 0 || size.height == 0 {
            return;
        }
        if let Some(p) = self.presenter.as_mut() {
            p.resize(size.width, size.height);
        }
        let (w, h) = self.options.internal_size(size.width, size.height);
        if (w, h) != (self.accum.width, self.accum.height) {
            self.accum = Accumulator::new(w, h);
            // The GPU renderer's buffers are the image's size: made again.
            self.shaded = None;
            self.gpu_samples = 0;
        }
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        event_loop.set_control_flow(ControlFlow::Wait);
        if let Err(e) = self.open_window(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => self.resized(size),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame(event_loop) {
                    self.fail(event_loop, e);
                }
            }
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.key(event_loop, &event.logical_key);
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.buttons.left = down,
                    MouseButton::Right => self.buttons.right = down,
                    MouseButton::Middle => self.buttons.middle = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some(last) = self.cursor {
                    let (dx, dy) = ((position.x - last.x) as f32, (position.y - last.y) as f32);
                    let b = self.buttons;
                    let height = self.window.as_ref().map_or(1, |w| w.inner_size().height);
                    if b.right || b.middle || (b.left && self.modifiers.shift_key()) {
                        self.orbit.drag_pan(dx, dy, height as f32);
                        self.moved = true;
                    } else if b.left {
                        self.orbit.drag_orbit(dx, dy);
                        self.moved = true;
                    }
                }
                self.cursor = Some(position);
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                if steps != 0.0 {
                    self.orbit.zoom(steps);
                    self.moved = true;
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        // Redraw while the image still changes; once it has its samples the
        // loop sleeps until input (or an expose) arrives.
        if self.busy()
            && let Some(w) = &self.window
        {
            w.request_redraw();
        }
    }
}
