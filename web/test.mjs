// The web page's browser test (run by web/test.sh): Debian's Chromium, headless
// on SwiftShader, loads the page for each demo scene on WebGL2 and on WebGPU,
// waits for frames, reads the renderer's frame back, and compares it with
// `glint render` of the same scene and camera (glint compare: the
// reference-image tolerance), and the tablecloth's once it has draped with
// `glint render --time` at that moment. A broken scene must show its file:line error, and
// a lost device its message.
// Prints one line per case and "N passed, M failed"; exits non-zero on a failure.
import { chromium } from "playwright-core";
import { execFileSync } from "node:child_process";
import { mkdirSync, readFileSync, writeFileSync } from "node:fs";

const [base, glint, out] = process.argv.slice(2);
const size = [256, 160];
const scenes = ["scenes/showcase.scn", "scenes/split.scn", "scenes/monitor.scn", "scenes/materials.scn"];
const backends = ["webgl2", "webgpu"];
mkdirSync(out, { recursive: true });

// SwiftShader's Vulkan for the compositor too: with ANGLE's GL there, Chromium finds no
// shared-image backing for a WebGPU canvas ("Could not find SharedImageBackingFactory ...
// WebgpuSwapChainTexture" in its log), destroys the device at the first present, and every
// later buffer map aborts ("A valid external Instance reference no longer exists").
const browser = await chromium.launch({
  executablePath: "/usr/bin/chromium",
  args: [
    "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--enable-unsafe-webgpu",
    "--enable-features=Vulkan", "--use-vulkan=swiftshader",
    "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run",
  ],
});
/** An init script timing the page's WebGL2 calls: milliseconds inside shader
 * compiling and linking with their status queries ("compile"), inside each
 * program's first useProgram ("first use": Chromium waits there for the link,
 * and for everything queued before it, so the first frame's present waits there
 * for the GPU process to draw the frame), texture uploads, draws, and all WebGL
 * calls, and the programs linked; `window.glintWebGL.first` holds the sums at
 * the first frame (data-frames turning 1). */
function timeWebGL() {
  const sums = { compile: 0, "first use": 0, textures: 0, draws: 0, gl: 0, programs: 0 };
  const kinds = {
    compile: ["compileShader", "linkProgram", "getShaderParameter", "getProgramParameter"],
    textures: ["texImage2D", "texSubImage2D", "texImage3D", "texSubImage3D", "texStorage2D", "texStorage3D", "generateMipmap"],
    draws: ["drawArrays", "drawElements", "drawArraysInstanced", "drawElementsInstanced", "drawRangeElements"],
  };
  const used = new WeakSet();
  const proto = WebGL2RenderingContext.prototype;
  for (const name of Object.getOwnPropertyNames(proto)) {
    const d = Object.getOwnPropertyDescriptor(proto, name);
    if (typeof d.value !== "function" || name === "constructor") continue;
    const call = d.value;
    proto[name] = function (...args) {
      let kind = Object.keys(kinds).find((k) => kinds[k].includes(name));
      if (name === "useProgram" && args[0] && !used.has(args[0])) {
        used.add(args[0]);
        kind = "first use";
      }
      if (name === "linkProgram") sums.programs++;
      const t = performance.now();
      try { return call.apply(this, args); } finally {
        const spent = performance.now() - t;
        sums.gl += spent;
        if (kind) sums[kind] += spent;
      }
    };
  }
  window.glintWebGL = { sums };
  new MutationObserver((_, observer) => {
    const canvas = document.getElementById("glint");
    if (+canvas?.dataset.frames >= 1) { window.glintWebGL.first = { ...sums }; observer.disconnect(); }
  }).observe(document, { attributes: true, subtree: true, attributeFilter: ["data-frames"] });
}

/** An init script noting when each of the first three frames is presented
 * (data-frames turning 1, 2, 3: `window.glintFrames`, ms) and when the GPU
 * has finished drawing the first (`window.glintDrawn`): its present returns
 * once its work is queued, and a software GPU draws it afterwards. WebGPU:
 * every queue submitted to is asked onSubmittedWorkDone; WebGL2: a fence,
 * polled. Neither blocks the page. */
function timeFrames() {
  window.glintFrames = [];
  const queues = new Set();
  let gl = null;
  if (window.GPUQueue) {
    const submit = GPUQueue.prototype.submit;
    GPUQueue.prototype.submit = function (...args) { queues.add(this); return submit.apply(this, args); };
  }
  const getContext = HTMLCanvasElement.prototype.getContext;
  HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
    const context = getContext.call(this, kind, ...rest);
    if (kind === "webgl2" && context) gl = context;
    return context;
  };
  new MutationObserver((_, observer) => {
    const frames = +document.getElementById("glint")?.dataset.frames;
    if (frames > window.glintFrames.length && frames <= 3) window.glintFrames.push(performance.now());
    if (frames === 1 && window.glintDrawn === undefined) {
      window.glintDrawn = null;
      if (gl) {
        const fence = gl.fenceSync(gl.SYNC_GPU_COMMANDS_COMPLETE, 0);
        gl.flush();
        const poll = () => gl.getSyncParameter(fence, gl.SYNC_STATUS) === gl.SIGNALED
          ? (window.glintDrawn = performance.now()) : setTimeout(poll, 5);
        poll();
      } else {
        Promise.all([...queues].map((q) => q.onSubmittedWorkDone())).then(() => { window.glintDrawn = performance.now(); });
      }
    }
    if (window.glintFrames.length >= 3) observer.disconnect();
  }).observe(document, { attributes: true, subtree: true, attributeFilter: ["data-frames"] });
}

let passed = 0, failed = 0;
const report = (ok, name, detail) => {
  ok ? passed++ : failed++;
  console.log(`${ok ? "ok  " : "FAIL"} ${name}: ${detail}`);
};

/** An init script: `window.glintAwaitFrames(n)` resolves once the page has
 * drawn `n` more frames (data-frames). */
function awaitFrames() {
  window.glintAwaitFrames = async (n) => {
    const canvas = document.getElementById("glint");
    const from = +canvas.dataset.frames;
    while (+canvas.dataset.frames < from + n) await new Promise((r) => requestAnimationFrame(r));
  };
}

/** Open the page on `scene` and `backend` (running the `init` scripts before the page's own,
 * adding `query` to the address); wait for 3 frames or an error. */
async function open(scene, backend, init = [], query = "") {
  const page = await browser.newPage({ viewport: { width: size[0] + 40, height: size[1] + 120 } });
  for (const script of [awaitFrames, ...init]) await page.addInitScript(script);
  const logs = [];
  page.on("console", (m) => logs.push(`${m.type()}: ${m.text()}`));
  page.on("pageerror", (e) => logs.push(`pageerror: ${e.message}`));
  const start = Date.now();
  await page.goto(`${base}/index.html?scene=${scene}&backend=${backend}&size=${size[0]}x${size[1]}${query}`);
  const state = await page
    .waitForFunction(() => {
      const c = document.getElementById("glint");
      return c.dataset.error ? { error: c.dataset.error } : +c.dataset.frames >= 1 && { first: performance.now() };
    }, null, { timeout: 90_000 })
    .then((h) => h.jsonValue())
    .catch((e) => ({ error: `no frame: ${e.message.split("\n")[0]}` }));
  if (!state.error) {
    await page.waitForFunction(() => +document.getElementById("glint").dataset.frames >= 3, null, { timeout: 90_000 });
  }
  return { page, state, logs, wall: Date.now() - start };
}

/** The share of the page's pixels whose colour moved by more than `threshold`
 * (summed over red, green and blue) over 3 frames. */
async function movedOver3Frames(page, threshold) {
  return page.evaluate(async (threshold) => {
    const a = await window.glintReadFrame();
    await window.glintAwaitFrames(3);
    const b = await window.glintReadFrame();
    let changed = 0;
    for (let i = 0; i < a.data.length; i += 4) {
      const d = Math.abs(a.data[i] - b.data[i]) + Math.abs(a.data[i + 1] - b.data[i + 1]) + Math.abs(a.data[i + 2] - b.data[i + 2]);
      if (d > threshold) changed++;
    }
    return changed / (a.width * a.height);
  }, threshold);
}

/** Read the page's frame back (as PNG, encoded by the browser), render `scene`
 * (the file at `path`, by default the repository's) with `glint render` at the
 * page's size and `args`, and compare the two with `glint compare` (the
 * reference-image tolerance); the images and the difference map are left in `out`. */
async function compareWithGlint(page, logs, scene, backend, args, path = scene) {
  const png = await page.evaluate(async () => {
    const f = await window.glintReadFrame();
    const canvas = new OffscreenCanvas(f.width, f.height);
    canvas.getContext("2d").putImageData(new ImageData(new Uint8ClampedArray(f.data), f.width, f.height), 0, 0);
    const bytes = new Uint8Array(await (await canvas.convertToBlob({ type: "image/png" })).arrayBuffer());
    let text = "";
    for (const b of bytes) text += String.fromCharCode(b);
    return btoa(text);
  }).catch((e) => ({ unread: String(e).split("\n")[0] }));
  if (png.unread) return { ok: false, verdict: `the frame could not be read back: ${png.unread}\n  ${logs.join("\n  ")}` };
  const stem = `${out}/${scene.replace(/[\/.]/g, "_")}_${backend}`;
  writeFileSync(`${stem}.page.png`, Buffer.from(png, "base64"));
  execFileSync(glint, ["render", path, "--size", `${size[0]}x${size[1]}`, "--msaa", "4", ...args, "-o", `${stem}.glint.png`]);
  try {
    const verdict = execFileSync(glint, ["compare", `${stem}.glint.png`, `${stem}.page.png`, "--diff", `${stem}.diff.png`]);
    return { ok: true, verdict: verdict.toString().trim() };
  } catch (e) {
    return { ok: false, verdict: `${e.stdout}${e.stderr}`.trim() };
  }
}

for (const backend of backends) {
  for (const scene of scenes) {
    const name = `${scene} on ${backend}`;
    const { page, state, logs } = await open(scene, backend);
    try {
      if (state.error) {
        report(false, name, `${state.error}\n  ${logs.join("\n  ")}`);
        continue;
      }
      const shown = await page.evaluate(() => document.getElementById("glint").dataset.backend);
      // The module the page loaded (index.html): the WebGPU-only one for WebGPU.
      const module = await page.evaluate(() => document.documentElement.dataset.module);
      // WebGPU culls on the GPU, WebGL2 (no compute) on the CPU.
      const culling = await page.evaluate(() => document.getElementById("glint").dataset.culling);
      const expected = backend === "webgpu" ? "WebGPU" : "WebGL2";
      const expectedCulling = backend === "webgpu" ? "gpu" : "cpu";
      const { ok: same, verdict } = await compareWithGlint(page, logs, scene, backend, []);
      const ok = same && shown === expected && culling === expectedCulling && module === backend;
      report(ok, name, `${shown} (module ${module}), culled on the ${culling}, first frame ${Math.round(state.first)} ms after navigation; ${verdict}`);
    } finally {
      await page.close();
    }
  }
}

// Without ?backend= the page picks the WebGPU module where the browser offers
// an adapter (this Chromium does), and runs on WebGPU.
{
  const { page, state, logs } = await open("scenes/showcase.scn", "");
  try {
    const module = await page.evaluate(() => document.documentElement.dataset.module);
    const shown = state.error ? null : await page.evaluate(() => document.getElementById("glint").dataset.backend);
    report(module === "webgpu" && shown === "WebGPU", "the page's own choice of module",
      `module ${module}, backend ${shown}${state.error ? `: ${state.error}\n  ${logs.join("\n  ")}` : ""}`);
  } finally {
    await page.close();
  }
}

// The showcase's startup, stage by stage as the page reports it (data-startup,
// startup.rs), median of five loads on each backend; every stage must be there.
// On WebGL2 the loads also time what the browser itself spends in its WebGL
// calls (timeWebGL): the floor under glint's "prepare" and "first frame" there.
// "total" ends when the first frame is presented, its work queued; the GPU
// (SwiftShader, on the CPU) draws it afterwards: when it has (timeFrames) is
// printed beside, and the second and third frames' mean time.
const STAGES = ["download", "instantiate", "gpu", "fetch", "decode", "load", "place", "waiting", "prepare", "first frame", "total"];
const CALLS = ["compile", "first use", "textures", "draws", "gl"];  // and "programs", a count
for (const backend of backends) {
  const loads = [];
  let why = "";
  for (let k = 0; k < 5 && !why; k++) {
    const init = backend === "webgl2" ? [timeFrames, timeWebGL] : [timeFrames];
    const { page, state, logs } = await open("scenes/showcase.scn", backend, init);
    try {
      const reported = state.error ? null : await page.evaluate(() => document.getElementById("glint").dataset.startup);
      const stages = reported ? JSON.parse(reported) : {};
      const missing = STAGES.filter((s) => !Number.isFinite(stages[s]));
      if (state.error || missing.length) why = `${state.error ?? `missing ${missing.join(", ")}`}\n  ${logs.join("\n  ")}`;
      else {
        const [one, , three] = await page.evaluate(() => window.glintFrames);
        const later = (three - one) / 2;
        await page.waitForFunction(() => Number.isFinite(window.glintDrawn), null, { timeout: 90_000 });
        const drawn = await page.evaluate(() => window.glintDrawn);
        loads.push({ ...stages, later, drawn, ...(await page.evaluate(() => window.glintWebGL?.first ?? {})) });
      }
    } finally {
      await page.close();
    }
  }
  const median = (name) => {
    const v = loads.map((l) => l[name]).sort((a, b) => a - b);
    return Math.round(v[v.length >> 1]);
  };
  const calls = backend === "webgl2"
    ? `; inside WebGL until the first frame: ${CALLS.map((c) => `${c} ${median(c)} ms`).join(", ")}` +
      ` (${median("programs")} programs linked)` : "";
  report(!why, `the showcase's startup on ${backend}`,
    why || `median of ${loads.length} loads: ${STAGES.map((s) => `${s} ${median(s)} ms`).join(", ")}${calls}; ` +
      `the first frame drawn by the GPU ${median("drawn")} ms after navigation; later frames ${median("later")} ms each`);
}

// The meadow (animated, so not compared with glint render): a tenth of every tile
// of its 1.08 million grass instances drawn (SwiftShader draws a frame of all of
// them in seconds); its first frame and frame time, and grass in the lower half.
for (const backend of backends) {
  const { page, state, logs } = await open("scenes/meadow.scn", backend, undefined, "&density=0.1");
  try {
    if (state.error) {
      report(false, `the meadow on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const timed = await page.evaluate(async () => {
      const canvas = document.getElementById("glint");
      const [from, start] = [+canvas.dataset.frames, performance.now()];
      while (+canvas.dataset.frames < from + 3) await new Promise((r) => requestAnimationFrame(r));
      const f = await window.glintReadFrame();
      let green = 0;
      for (let y = f.height >> 1; y < f.height; y++) {
        for (let x = 0; x < f.width; x++) {
          const i = 4 * (y * f.width + x);
          if (f.data[i + 1] > f.data[i] && f.data[i + 1] > f.data[i + 2]) green++;
        }
      }
      return { ms: (performance.now() - start) / 3, green: green / (f.width * (f.height - (f.height >> 1))) };
    });
    const culling = await page.evaluate(() => document.getElementById("glint").dataset.culling);
    const ok = timed.green > 0.5 && culling === (backend === "webgpu" ? "gpu" : "cpu");
    report(ok, `the meadow on ${backend}`,
      `culled on the ${culling}, first frame ${Math.round(state.first)} ms after navigation, ` +
      `then ${Math.round(timed.ms)} ms a frame; ${Math.round(100 * timed.green)} % of the lower half grass`);
  } finally {
    await page.close();
  }
}

// The aquarium runs live: its fish school and bubbles step with the page's
// clock (the bubbles with compute shaders on WebGPU, on the CPU on WebGL2), so
// two frames a while apart differ.
for (const backend of backends) {
  const { page, state, logs } = await open("scenes/aquarium.scn", backend);
  try {
    if (state.error) {
      report(false, `the aquarium on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const moved = await movedOver3Frames(page, 48);
    report(moved > 0.002, `the aquarium on ${backend}`,
      `first frame ${Math.round(state.first)} ms after navigation; ${(100 * moved).toFixed(1)} % of pixels moved over 3 frames`);
  } finally {
    await page.close();
  }
}

// The night square's 1,264 lights are shaded from each view's light clusters
// (storage buffers on WebGPU, a data texture on WebGL2), its 1,000 fireflies
// circling with the page's clock: two frames a while apart differ, and paused
// once it has run a while, the page's picture is `glint render --time` at
// the same time.
for (const backend of backends) {
  const scene = "scenes/lights.scn";
  const { page, state, logs } = await open(scene, backend);
  try {
    if (state.error) {
      report(false, `the lights on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const moved = await movedOver3Frames(page, 24);
    const time = await page.evaluate(async () => {
      document.querySelector('[data-control="paused"]').click();
      await window.glintAwaitFrames(1);
      return document.getElementById("glint").dataset.time;
    });
    const { ok, verdict } = await compareWithGlint(page, logs, scene, backend, ["--time", time]);
    // Where the page binned its lights (the CPU on WebGL2, the GPU on WebGPU),
    // and the CPU's milliseconds, the median of 15 paused frames.
    const binning = await page.evaluate(async () => {
      const samples = [];
      for (let k = 0; k < 15; k++) {
        await window.glintAwaitFrames(1);
        samples.push(document.getElementById("glint").dataset.lightBinning.split(" "));
      }
      const ms = samples.map((s) => Number(s[1])).sort((a, b) => a - b);
      return { where: samples[0][0], ms: ms[7] };
    });
    const binnedWhere = binning.where === (backend === "webgpu" ? "gpu" : "cpu");
    // Its heat map of lights per cluster (the controls' toggle) is `glint render --cluster-heat`'s.
    await page.evaluate(async () => {
      document.querySelector('[data-control="cluster_heat"]').click();
      await window.glintAwaitFrames(2);
    });
    const heat = await compareWithGlint(page, logs, "scenes/lights_heat", backend, ["--time", time, "--cluster-heat"], scene);
    report(ok && heat.ok && binnedWhere && moved > 0.001, `the lights on ${backend}`,
      `${(100 * moved).toFixed(2)} % of pixels moved over 3 frames; paused at ${time} s; ${verdict}; ` +
      `binned on the ${binning.where}, ${binning.ms.toFixed(3)} ms of the CPU a frame (median of 15); heat map: ${heat.verdict}`);
  } finally {
    await page.close();
  }
}

// A school steps on the GPU and is drawn from its own buffers with WebGPU,
// on the CPU with WebGL2 (tests/scenes/school.scn with cubes for fish,
// written by test.sh):
// paused once it has swum a second, the page's picture is `glint render
// --time` at the same time on the same path.
for (const backend of backends) {
  const scene = "scenes/school.scn";
  const { page, state, logs } = await open(scene, backend);
  try {
    if (state.error) {
      report(false, `a school on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const { time, simulations } = await page.evaluate(async () => {
      const canvas = document.getElementById("glint");
      const frames = window.glintAwaitFrames;
      while (+canvas.dataset.time < 1) await frames(1);
      document.querySelector('[data-control="paused"]').click();
      await frames(1);
      return { time: canvas.dataset.time, simulations: canvas.dataset.simulations };
    });
    const path = backend === "webgpu" ? "gpu" : "cpu";
    const args = ["--time", time, "--sim", path];
    const { ok, verdict } = await compareWithGlint(page, logs, scene, backend, args, `web/dist/${scene}`);
    const stepped = simulations === `school on the ${path.toUpperCase()}`;
    report(ok && stepped, `a school on ${backend}`, `${simulations}; paused at ${time} s; ${verdict}`);
  } finally {
    await page.close();
  }
}

// Cloth solved on the GPU and drawn from its buffers with WebGPU, converged
// on the CPU with WebGL2 (tests/scenes/cloth_gpu.scn, copied by test.sh):
// paused once the sheets have swung and fallen a while, the page's picture is
// `glint render --time` at the same time on the same path.
for (const backend of backends) {
  const scene = "scenes/cloth_gpu.scn";
  const { page, state, logs } = await open(scene, backend);
  try {
    if (state.error) {
      report(false, `cloth on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const { time, simulations } = await page.evaluate(async () => {
      const canvas = document.getElementById("glint");
      const frames = window.glintAwaitFrames;
      while (+canvas.dataset.time < 0.3) await frames(1);
      document.querySelector('[data-control="paused"]').click();
      await frames(1);
      return { time: canvas.dataset.time, simulations: canvas.dataset.simulations };
    });
    const path = backend === "webgpu" ? "GPU" : "CPU";
    const args = ["--time", time, "--solve", backend === "webgpu" ? "gpu" : "converged"];
    const { ok, verdict } = await compareWithGlint(page, logs, scene, backend, args, `web/dist/${scene}`);
    const stepped = simulations === `2 cloths on the ${path}`;
    report(ok && stepped, `cloth on ${backend}`, `${simulations}; paused at ${time} s; ${verdict}`);
  } finally {
    await page.close();
  }
}

// The underwater scene: 24,000 fish schooling, drawn at the levels of detail
// their size on screen needs (the panel can turn them off).
for (const backend of backends) {
  const { page, state, logs } = await open("scenes/underwater.scn", backend);
  try {
    if (state.error) {
      report(false, `the 24,000 fish on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const seen = await page.evaluate(async () => {
      const f = await window.glintReadFrame();
      // The fish: pixels of the upper half (the water; the sand is below)
      // away from their row's median colour, the water's.
      let fish = 0;
      const rows = f.height >> 1;
      for (let y = 0; y < rows; y++) {
        const row = f.data.subarray(4 * y * f.width, 4 * (y + 1) * f.width);
        const median = [0, 1, 2].map((c) => {
          const v = [];
          for (let x = 0; x < f.width; x++) v.push(row[4 * x + c]);
          v.sort((a, b) => a - b);
          return v[v.length >> 1];
        });
        for (let x = 0; x < f.width; x++) {
          const d = [0, 1, 2].reduce((sum, c) => sum + Math.abs(row[4 * x + c] - median[c]), 0);
          if (d > 24) fish++;
        }
      }
      const control = document.querySelector('#controls [data-control="levels"]');
      return { fish: fish / (f.width * rows), control: control !== null };
    });
    report(seen.fish > 0.03 && seen.control, `the 24,000 fish on ${backend}`,
      `first frame ${Math.round(state.first)} ms after navigation; ${(100 * seen.fish).toFixed(1)} % of the upper half fish; ` +
      `levels-of-detail control ${seen.control ? "shown" : "missing"}`);
  } finally {
    await page.close();
  }
}

// The tablecloth falls onto its table as it does natively: the page's cloth
// (faer's simplicial factorisations and plain loops in the wasm module, where
// glint natively may use supernodal ones and rayon) is paused once it has
// struck the table, and compared with `glint render --time` at the same time.
for (const backend of backends) {
  const scene = "scenes/tablecloth.scn";
  const { page, state, logs } = await open(scene, backend);
  try {
    if (state.error) {
      report(false, `the tablecloth on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const time = await page.evaluate(async () => {
      const canvas = document.getElementById("glint");
      const frames = window.glintAwaitFrames;
      while (+canvas.dataset.time < 0.3) await frames(1);
      document.querySelector('[data-control="paused"]').click();
      await frames(1);
      return canvas.dataset.time;
    });
    const { ok, verdict } = await compareWithGlint(page, logs, scene, backend, ["--time", time]);
    report(ok, `the tablecloth on ${backend}`, `paused at ${time} s; ${verdict}`);
  } finally {
    await page.close();
  }
}

// A JPEG stored sideways, with the EXIF orientation that turns it upright
// (web/test.sh writes the scene): the browser turns it as it decodes it, and
// glint's own decoder does the same.
for (const backend of backends) {
  const scene = "scenes/turned.scn";
  const { page, state, logs } = await open(scene, backend);
  try {
    const { ok, verdict } = state.error
      ? { ok: false, verdict: `${state.error}\n  ${logs.join("\n  ")}` }
      : await compareWithGlint(page, logs, scene, backend, [], `web/dist/${scene}`);
    report(ok, `a JPEG turned by its EXIF orientation on ${backend}`, verdict);
  } finally {
    await page.close();
  }
}

// The controls beside the canvas change what they claim, as the canvas's
// numbers show: shadows off leaves no shadow views, a lower density draws
// fewer instances, and pausing stops the scene clock.
for (const backend of backends) {
  const { page, state, logs } = await open("scenes/meadow.scn", backend, undefined, "&density=0.1");
  try {
    if (state.error) {
      report(false, `the controls on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const result = await page.evaluate(async () => {
      const canvas = document.getElementById("glint");
      const frames = window.glintAwaitFrames;
      const control = (id) => document.querySelector(`[data-control="${id}"]`);
      if (!control("shadows") || !control("density") || !control("paused")) return { missing: document.getElementById("controls").textContent };
      await frames(4);  // counts culled on the GPU come back a frame or two late
      const before = { shadows: +canvas.dataset.shadowViews, instances: +canvas.dataset.instances };
      control("shadows").click();
      const density = control("density");
      density.value = "0.05";
      density.dispatchEvent(new Event("input"));
      // Counts culled on the GPU come back when the browser maps them: a few frames.
      for (let k = 0; k < 12 && (k < 3 || +canvas.dataset.instances === before.instances); k++) await frames(1);
      const after = { shadows: +canvas.dataset.shadowViews, instances: +canvas.dataset.instances };
      control("paused").click();
      await frames(1);
      const t1 = canvas.dataset.time;
      await frames(2);
      return { before, after, t1, t2: canvas.dataset.time };
    });
    if (result.missing !== undefined) {
      report(false, `the controls on ${backend}`, `no shadows, density or paused control: ${result.missing}`);
      continue;
    }
    const { before, after, t1, t2 } = result;
    const ok = before.shadows > 0 && after.shadows === 0 && after.instances * 1.5 < before.instances && t1 === t2;
    report(ok, `the controls on ${backend}`,
      `shadow views ${before.shadows} then ${after.shadows}; instances ${before.instances} then ${after.instances}; ` +
      `paused at ${t1} s, still ${t2} s two frames later`);
  } finally {
    await page.close();
  }
}

// How far the page's frame is from the PNG at `path`, pixel by pixel: the mean
// and the largest difference of a colour channel, in levels of 255.
async function pixelDifference(page, path) {
  const png = readFileSync(path).toString("base64");
  return page.evaluate(async (png) => {
    const f = await window.glintReadFrame();
    const bitmap = await createImageBitmap(await (await fetch(`data:image/png;base64,${png}`)).blob());
    const canvas = new OffscreenCanvas(f.width, f.height);
    const context = canvas.getContext("2d");
    context.drawImage(bitmap, 0, 0);
    const other = context.getImageData(0, 0, f.width, f.height).data;
    const page = new Uint8Array(f.data);
    let sum = 0, most = 0, count = 0;
    for (let k = 0; k < page.length; k++) {
      if (k % 4 === 3) continue;
      const d = Math.abs(page[k] - other[k]);
      sum += d; most = Math.max(most, d); count++;
    }
    return { mean: sum / count, most };
  }, png);
}

// Soft shadows on the page are `glint render`'s, and its samples-per-pixel
// control draws each frame as the accumulated still `glint render --spp 16`
// does. The still is checked pixel by pixel (a mean under 1 level, none past
// 32): the reference tolerance's structural similarity marks down the ±1
// rounding of SwiftShader against lavapipe across the average's smooth
// gradients (0.969 where a single sample scores 0.98) though no pixel is off by 20.
for (const backend of backends) {
  const scene = "scenes/soft_shadows.scn";
  const { page, state, logs } = await open(scene, backend);
  try {
    if (state.error) {
      report(false, `soft shadows and a still on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const soft = await compareWithGlint(page, logs, scene, backend, [], "tests/scenes/soft_shadows.scn");
    const chosen = await page.evaluate(async () => {
      const control = (id) => document.querySelector(`[data-control="${id}"]`);
      if (!control("samples") || !control("sun_size")) return false;
      control("paused").click();
      control("samples").value = "2";
      control("samples").dispatchEvent(new Event("change"));
      await window.glintAwaitFrames(2);
      return true;
    });
    let still = { ok: false, verdict: "no samples or sun size control" };
    if (chosen) {
      const file = `${out}/soft_shadows_still_${backend}.glint.png`;
      execFileSync(glint, ["render", "tests/scenes/soft_shadows.scn", "--size", `${size[0]}x${size[1]}`, "--msaa", "4", "--spp", "16", "-o", file]);
      const { mean, most } = await pixelDifference(page, file);
      still = { ok: mean < 1 && most <= 32, verdict: `mean difference ${mean.toFixed(3)}, largest ${most} (of 255)` };
    }
    report(soft.ok && still.ok, `soft shadows and a still on ${backend}`, `one sample: ${soft.verdict}; 16 samples: ${still.verdict}`);
  } finally {
    await page.close();
  }
}

// SMAA on the page is `glint render`'s (its three passes on WebGL2 and
// WebGPU), and the anti-aliasing control's "none" takes it out of the chain
// as `glint render --post tonemap` does.
for (const backend of backends) {
  const scene = "scenes/smaa.scn";
  const { page, state, logs } = await open(scene, backend);
  try {
    if (state.error) {
      report(false, `SMAA on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const smaa = await compareWithGlint(page, logs, scene, backend, [], "tests/scenes/smaa.scn");
    const chosen = await page.evaluate(async () => {
      const control = document.querySelector('[data-control="antialiasing"]');
      if (!control) return false;
      control.value = "1";
      control.dispatchEvent(new Event("change"));
      await window.glintAwaitFrames(2);
      return true;
    });
    let none = { ok: false, verdict: "no anti-aliasing control" };
    if (chosen) none = await compareWithGlint(page, logs, "scenes/smaa_none.scn", backend, ["--post", "tonemap"], "tests/scenes/smaa.scn");
    report(smaa.ok && none.ok, `SMAA on ${backend}`, `SMAA: ${smaa.verdict}; none: ${none.verdict}`);
  } finally {
    await page.close();
  }
}

// Weighted transparency on the page is `glint render --transparency
// weighted`'s, the control offers sorted and weighted (not exact, which keeps
// per-pixel lists that browsers' shaders cannot), and a scene asking for
// exact is refused with that reason.
for (const backend of backends) {
  const scene = "scenes/transparency.scn";
  const { page, state, logs } = await open(scene, backend);
  try {
    if (state.error) {
      report(false, `transparency on ${backend}`, `${state.error}\n  ${logs.join("\n  ")}`);
      continue;
    }
    const path = "tests/scenes/transparency.scn";
    const weighted = await compareWithGlint(page, logs, scene, backend, ["--transparency", "weighted"], path);
    const options = await page.evaluate(async () => {
      const control = document.querySelector('[data-control="transparency"]');
      if (!control) return null;
      const names = [...control.options].map((o) => o.textContent);
      control.value = "0";
      control.dispatchEvent(new Event("change"));
      await window.glintAwaitFrames(2);
      return names;
    });
    let sorted = { ok: false, verdict: "no transparency control" };
    if (options) sorted = await compareWithGlint(page, logs, "scenes/transparency_sorted.scn", backend, ["--transparency", "sorted"], path);
    const offered = JSON.stringify(options) === JSON.stringify(["sorted", "weighted"]);
    report(weighted.ok && sorted.ok && offered, `transparency on ${backend}`, `weighted: ${weighted.verdict}; sorted: ${sorted.verdict}; offered ${JSON.stringify(options)}`);
  } finally {
    await page.close();
  }
  const exact = await open("scenes/transparency_exact.scn", backend);
  const said = exact.state.error || "";
  report(said.includes("exact transparency is not available"), `exact transparency refused on ${backend}`, JSON.stringify(said));
  await exact.page.close();
}

// A broken scene shows its error, with the file and line, on the page.
for (const backend of backends) {
  const { page, state } = await open("scenes/broken.scn", backend);
  const text = await page.evaluate(() => document.getElementById("error").textContent);
  const ok = !!state.error && text.startsWith("scenes/broken.scn:3:");
  report(ok, `a broken scene on ${backend}`, JSON.stringify(text));
  await page.close();
}
// A missing scene says so too.
{
  const { page, state } = await open("scenes/missing.scn", "webgl2");
  const text = await page.evaluate(() => document.getElementById("error").textContent);
  report(!!state.error && text.includes("scenes/missing.scn") && text.includes("not found"), "a missing scene", JSON.stringify(text));
  await page.close();
}
// A lost WebGPU device is reported on the page, not left as a frozen frame.
{
  const keepDevice = () => {
    const request = GPUAdapter.prototype.requestDevice;
    GPUAdapter.prototype.requestDevice = async function (...args) {
      return (window.glintTestDevice = await request.apply(this, args));
    };
  };
  const { page, state } = await open("scenes/split.scn", "webgpu", [keepDevice]);
  await page.evaluate(() => window.glintTestDevice.destroy());
  const text = await page
    .waitForFunction(() => document.getElementById("glint").dataset.error, null, { timeout: 30_000 })
    .then(() => page.evaluate(() => document.getElementById("error").textContent))
    .catch(() => "no error shown");
  report(!state.error && text.startsWith("the WebGPU device was lost"), "a lost device on webgpu", JSON.stringify(text));
  await page.close();
}
await browser.close();
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed === 0 ? 0 : 1);
