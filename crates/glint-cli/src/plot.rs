//! `glint bench --plot`: the median CPU time of each frame stage as a bar chart,
//! one panel per mode, drawn with plotters into a PNG.

use crate::bench::ModeReport;
use glint::Diagnostic;
use plotters::prelude::*;
use std::path::Path;

/// DejaVu Sans (see `assets/fonts/DejaVuSans-LICENSE.txt`): bundled so charts
/// have labels on machines without system fonts.
const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

/// The stages of `StageTimes`, in frame order.
const STAGES: [&str; 8] = ["prepare", "cull", "queue", "sort", "batch", "upload", "encode", "submit"];

const PANEL: (u32, u32) = (560, 380);

fn stage_values(r: &ModeReport) -> [f64; 8] {
    let s = &r.stage_ms_median;
    [s.prepare, s.cull, s.queue, s.sort, s.batch, s.upload, s.encode, s.submit]
}

/// Draw the stage breakdown of `reports` under `title` into the PNG at `path`.
pub fn stage_chart(path: &Path, title: &str, reports: &[ModeReport]) -> Result<(), Diagnostic> {
    let fail = |e: &dyn std::fmt::Display| Diagnostic::file(path, format!("cannot draw the chart: {e}"));
    // Registering twice (a second chart in one process) replaces the same font.
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| fail(&"the bundled font is invalid"))?;
    let (width, height) = (PANEL.0 * reports.len().max(1) as u32, PANEL.1);
    let mut pixels = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let root = root.titled(title, ("sans-serif", 18)).map_err(|e| fail(&e))?;
        for (panel, report) in root.split_evenly((1, reports.len().max(1))).iter().zip(reports) {
            let values = stage_values(report);
            let top = values.iter().copied().fold(1e-6, f64::max) * 1.15;
            let caption = format!("{}: {:.4} ms a frame (median)", report.mode, report.cpu_ms_median);
            let mut chart = ChartBuilder::on(panel)
                .caption(caption, ("sans-serif", 15))
                .margin(12)
                .x_label_area_size(30)
                .y_label_area_size(64)
                .build_cartesian_2d((0..STAGES.len() - 1).into_segmented(), 0.0..top)
                .map_err(|e| fail(&e))?;
            chart
                .configure_mesh()
                .disable_x_mesh()
                .x_labels(STAGES.len())
                .x_label_formatter(&|x| match x {
                    SegmentValue::CenterOf(i) => STAGES.get(*i).copied().unwrap_or_default().to_string(),
                    _ => String::new(),
                })
                .y_desc("CPU ms (median)")
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(|e| fail(&e))?;
            let bars = values.iter().enumerate().map(|(i, &ms)| (i, ms));
            chart
                .draw_series(Histogram::vertical(&chart).style(RGBColor(70, 110, 190).filled()).margin(8).data(bars))
                .map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    let image = image::RgbImage::from_raw(width, height, pixels).expect("buffer is width × height × 3");
    let bytes = crate::output::png_bytes(&image).map_err(|e| fail(&e))?;
    crate::output::write_file(path, &bytes)
}
