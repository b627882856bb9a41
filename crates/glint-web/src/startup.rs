//! The page's startup, stage by stage: download (navigation to the module's
//! last byte), instantiate (to the module running), gpu (adapter and device),
//! fetch (the scene and its files over HTTP), decode (the browser decoding its
//! PNG and JPEG images), load (parsing them and decoding the rest),
//! place (the scene on the GPU), waiting (the controls panel, and the wait
//! for the first animation frame), prepare (the first frame's preparation,
//! its shadow passes' included: shader variants composed, pipelines made,
//! first uploads), first frame (the rest of it, to its presentation). Reported once, on the page (`#startup`), in the
//! console and as the canvas's `data-startup` (JSON: each stage's milliseconds
//! and `total`, from navigation), for `web/test.mjs`.

/// The stages measured so far and when the last one ended (page time, ms).
pub struct Startup {
    stages: Vec<(&'static str, f64)>,
    last: f64,
}

/// Milliseconds since the page's navigation started.
pub fn now() -> f64 {
    web_sys::window().and_then(|w| w.performance()).map_or(0.0, |p| p.now())
}

impl Startup {
    /// Begun as the module starts running: its download and instantiation are over.
    pub fn begin() -> Self {
        let start = now();
        let downloaded = module_downloaded().unwrap_or(start).min(start);
        Self { stages: vec![("download", downloaded), ("instantiate", start - downloaded)], last: start }
    }

    /// End stage `name` now.
    pub fn lap(&mut self, name: &'static str) {
        let t = now();
        self.stages.push((name, t - self.last));
        self.last = t;
    }

    /// End stages `inner` (each with its milliseconds, measured inside) and
    /// `name` (the rest) now.
    pub fn split(&mut self, inner: &[(&'static str, f64)], name: &'static str) {
        let t = now();
        let mut rest = t - self.last;
        for &(stage, ms) in inner {
            self.stages.push((stage, ms.min(rest)));
            rest = (rest - ms).max(0.0);
        }
        self.stages.push((name, rest));
        self.last = t;
    }

    /// Show the stages on the page, in the console and on the canvas.
    pub fn report(&self, canvas: &web_sys::HtmlCanvasElement) {
        let total = self.last;
        let stages: Vec<String> = self.stages.iter().map(|(name, ms)| format!("{name} {ms:.0}")).collect();
        let line = format!("first frame after {total:.0} ms: {}", stages.join(", "));
        web_sys::console::log_1(&format!("glint startup: {line}").into());
        super::set_text("startup", &line);
        let json = js_sys::Object::new();
        for (name, ms) in self.stages.iter().chain(std::iter::once(&("total", total))) {
            let _ = js_sys::Reflect::set(&json, &(*name).into(), &(*ms).into());
        }
        if let Ok(text) = js_sys::JSON::stringify(&json) {
            let _ = canvas.set_attribute("data-startup", &String::from(text));
        }
    }
}

/// When the module's last byte arrived (resource timing of `glint_web_*_bg.wasm`).
fn module_downloaded() -> Option<f64> {
    let performance = web_sys::window()?.performance()?;
    let entries = performance.get_entries_by_type("resource");
    entries.iter().find_map(|entry| {
        let name = js_sys::Reflect::get(&entry, &"name".into()).ok()?.as_string()?;
        let end = js_sys::Reflect::get(&entry, &"responseEnd".into()).ok()?.as_f64()?;
        name.ends_with("_bg.wasm").then_some(end)
    })
}
