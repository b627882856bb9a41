//! Checked output. Everything glint prints or writes (statistics, reports, PNG
//! frames and charts, CSV trajectories) goes through here: each write is
//! checked and flushed, and a failed one is an error naming the path (exit 1),
//! never a panic (`println!` panics on a full stdout) nor a silent exit 0 (a
//! file's last buffered bytes are lost when a writer is dropped unflushed).

use glint::{Diagnostic, Error, Gpu, OffscreenTarget};
use std::io::Write;
use std::path::Path;

/// How standard output is named in messages.
pub const STDOUT: &str = "standard output";

/// The diagnostic for a failed write to `path`.
pub fn write_failed(path: &Path, e: &std::io::Error) -> Diagnostic {
    Diagnostic::file(path, format!("cannot write: {e}"))
}

/// Write `text` to standard output and flush it.
pub fn print(text: &str) -> Result<(), Diagnostic> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes()).and_then(|()| out.flush()).map_err(|e| write_failed(Path::new(STDOUT), &e))
}

/// Create (or truncate) `path` and write `bytes` to it, flushed.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), Diagnostic> {
    let mut file = std::fs::File::create(path).map_err(|e| Diagnostic::file(path, format!("cannot create: {e}")))?;
    file.write_all(bytes).and_then(|()| file.flush()).map_err(|e| write_failed(path, &e))
}

/// Write `bytes` to `path` whole or not at all: into a `.part` file beside
/// it, renamed to `path` once written, so a run killed midway leaves no
/// truncated frame that `--skip-existing` would keep.
pub fn write_file_whole(path: &Path, bytes: &[u8]) -> Result<(), Diagnostic> {
    let mut part = path.as_os_str().to_owned();
    part.push(".part");
    let part = std::path::PathBuf::from(part);
    write_file(&part, bytes)?;
    std::fs::rename(&part, path).map_err(|e| Diagnostic::file(path, format!("cannot write: {e}")))
}

/// `image` (RGBA8 or RGB8) encoded as PNG, in memory.
pub fn png_bytes<P>(image: &image::ImageBuffer<P, Vec<u8>>) -> Result<Vec<u8>, image::ImageError>
where
    P: image::Pixel<Subpixel = u8> + image::PixelWithColorType,
{
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png)?;
    Ok(bytes.into_inner())
}

/// Read `target`'s last frame back and write it to `path` as PNG.
pub fn save_png(gpu: &Gpu, target: &OffscreenTarget, path: &Path) -> Result<(), Error> {
    let image = target.read_rgba8(gpu)?;
    let bytes = png_bytes(&image).map_err(|e| Diagnostic::file(path, format!("cannot encode the PNG: {e}")))?;
    Ok(write_file(path, &bytes)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_device_is_an_error_naming_the_path() {
        let full = Path::new("/dev/full");
        if !full.exists() {
            return;
        }
        let err = write_file(full, b"frame").unwrap_err();
        assert_eq!(err.path, full);
        assert!(err.message.starts_with("cannot write: "), "{err}");
    }

    #[test]
    fn png_bytes_decode_back_to_the_image() {
        let image = image::RgbaImage::from_fn(3, 2, |x, y| image::Rgba([x as u8 * 80, y as u8 * 90, 7, 255]));
        let bytes = png_bytes(&image).unwrap();
        let back = image::load_from_memory(&bytes).unwrap().to_rgba8();
        assert_eq!(back, image);
    }
}
