// The page: opens a scene on the canvas through dirt-web (wasm), steps one
// sample pass at a time, and applies camera moves between passes. URL
// parameters: scene=NAME, backend=auto|gpu|cpu, spp=N (stop after N passes),
// size=WxH (the image; the canvas is scaled to 640x480).
import init, { open_page, builtin_scenes, check_builtin } from "./pkg/dirt_web.js";

const params = new URLSearchParams(location.search);
let canvas = document.getElementById("view");
const status = document.getElementById("status");
const stats = document.getElementById("stats");
const warning = document.getElementById("warning");
const sceneSelect = document.getElementById("scene");
const backendSelect = document.getElementById("backend");
const maxSamples = Number(params.get("spp") || Infinity);
const [w, h] = (params.get("size") || "160x120").split("x").map(Number);

// A canvas keeps the kind of context it was first given (WebGPU for the GPU
// backend, which presents there; 2D for the CPU's): each page gets a fresh one.
function freshCanvas() {
  const c = canvas.cloneNode(false);
  c.width = w;
  c.height = h;
  canvas.replaceWith(c);
  canvas = c;
  let drag = null;
  c.onpointerdown = (e) => { drag = [e.clientX, e.clientY]; c.setPointerCapture(e.pointerId); };
  c.onpointerup = () => { drag = null; };
  c.onpointermove = (e) => {
    if (!drag) return;
    // Drag in image pixels, whatever the canvas is scaled to.
    const k = c.width / c.clientWidth;
    pending.dx += (e.clientX - drag[0]) * k;
    pending.dy += (e.clientY - drag[1]) * k;
    drag = [e.clientX, e.clientY];
  };
  c.onwheel = (e) => { e.preventDefault(); pending.zoom += e.deltaY < 0 ? 1 : -1; };
}

let page = null;
let generation = 0;
let pending = { dx: 0, dy: 0, zoom: 0 };

function show(message, isError) {
  status.textContent = message;
  status.dataset.state = isError ? "error" : "ok";
}

async function open(scene, file) {
  const mine = ++generation;
  page = null;
  show(`opening ${scene}…`);
  freshCanvas();
  try {
    const p = await open_page(canvas, scene, file ?? undefined, backendSelect.value);
    if (mine !== generation) return;
    page = p;
    show(p.status());
    stats.dataset.camera = p.camera_args();
    loop(mine);
  } catch (e) {
    fallBack(e);
  }
}

// With backend "auto", a WebGPU failure (a device lost, a read-back refused)
// reopens the scene on the CPU and says why; otherwise it is an error.
function fallBack(e) {
  const why = e.message ?? String(e);
  if (backendSelect.value === "auto" && !page?.status().includes("CPU")) {
    warning.hidden = false;
    warning.textContent = `WebGPU failed (${why}): dirt runs on the CPU in wasm instead.`;
    backendSelect.value = "cpu";
    open(sceneSelect.value);
  } else {
    show(`error: ${why}`, true);
  }
}

async function loop(mine) {
  while (page && mine === generation) {
    if (pending.dx || pending.dy || pending.zoom) {
      if (pending.dx || pending.dy) page.orbit(pending.dx, pending.dy);
      if (pending.zoom) page.zoom(pending.zoom);
      pending = { dx: 0, dy: 0, zoom: 0 };
      stats.dataset.camera = page.camera_args();
    }
    if (page.samples() >= maxSamples) {
      stats.dataset.done = "1";
      await new Promise((r) => setTimeout(r, 100));
      continue;
    }
    try {
      await page.step();
    } catch (e) {
      fallBack(e);
      return;
    }
    const n = page.samples();
    stats.dataset.samples = String(n);
    stats.textContent = `${n} samples   ${(page.rays_per_second() / 1e6).toFixed(3)} Mrays/s\n${page.camera_args()}`;
    // Let the browser draw and take input between passes.
    await new Promise((r) => requestAnimationFrame(() => r()));
  }
}

async function main() {
  await init();
  // For tests and the curious: dirt.check("cornell", 32, 4, 1000) measures
  // DIRT on this page's WebGPU against the CPU reference (structure and hits).
  window.dirt = { check: check_builtin };
  if (!navigator.gpu) {
    warning.hidden = false;
    warning.textContent =
      "This browser has no WebGPU (navigator.gpu is missing): dirt runs on the CPU in wasm instead, much slower. " +
      "Chrome/Chromium 113+ and Edge have it; on Linux start Chromium with --enable-unsafe-webgpu.";
  } else if (!(await navigator.gpu.requestAdapter())) {
    warning.hidden = false;
    warning.textContent = "This browser has WebGPU but gives no adapter: dirt runs on the CPU in wasm instead.";
  }
  for (const name of builtin_scenes()) {
    const o = document.createElement("option");
    o.value = o.textContent = name;
    sceneSelect.append(o);
  }
  sceneSelect.value = params.get("scene") || "cornell";
  backendSelect.value = params.get("backend") || "auto";
  sceneSelect.onchange = () => open(sceneSelect.value);
  backendSelect.onchange = () => open(sceneSelect.value);

  const drop = document.getElementById("drop");
  drop.ondragover = (e) => { e.preventDefault(); drop.classList.add("over"); };
  drop.ondragleave = () => drop.classList.remove("over");
  drop.ondrop = async (e) => {
    e.preventDefault();
    drop.classList.remove("over");
    const f = e.dataTransfer.files[0];
    if (f) open(f.name, new Uint8Array(await f.arrayBuffer()));
  };
  open(sceneSelect.value);
}

main().catch((e) => show(`error: ${e.message ?? e}`, true));
