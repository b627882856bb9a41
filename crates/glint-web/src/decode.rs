//! PNG and JPEG decoding by the browser, for a [`glint::asset::FileSet`] made
//! with `host_decoding`: the page ships no decoder of its own. Each image is
//! decoded off the main thread (`createImageBitmap`, with no premultiplied
//! alpha and no colour conversion, as glint's own decoder reads it) and its
//! pixels read back exactly through a WebGL2 texture (a 2D canvas would store
//! them premultiplied and round away colour where alpha is low).

use std::sync::Arc;
use wasm_bindgen::{JsCast, JsValue};
use wasm_bindgen_futures::JsFuture;
use web_sys::WebGl2RenderingContext as Gl;

/// Decoded images: width, height and RGBA8 pixels top row first, or why not.
pub type Decoded = Result<(u32, u32, Vec<u8>), String>;

/// Decode every image in `encoded` (each at most once), all started before the
/// first is awaited, pairing each with its result.
pub async fn decode_all(mut encoded: Vec<Arc<[u8]>>) -> Result<Vec<(Arc<[u8]>, Decoded)>, String> {
    encoded.sort_unstable();
    encoded.dedup();
    if encoded.is_empty() {
        return Ok(Vec::new()); // no WebGL2 context made for nothing
    }
    let window = web_sys::window().ok_or("no window")?;
    let options = web_sys::ImageBitmapOptions::new();
    options.set_premultiply_alpha(web_sys::PremultiplyAlpha::None);
    options.set_color_space_conversion(web_sys::ColorSpaceConversion::None);
    let started: Vec<_> = encoded
        .into_iter()
        .map(|bytes| {
            let parts = js_sys::Array::of1(&js_sys::Uint8Array::from(&bytes[..]));
            let bitmap = web_sys::Blob::new_with_u8_array_sequence(&parts)
                .and_then(|blob| window.create_image_bitmap_with_blob_and_image_bitmap_options(&blob, &options));
            (bytes, bitmap.map(JsFuture::from))
        })
        .collect();
    let reader = Reader::new()?;
    let mut decoded = Vec::with_capacity(started.len());
    for (bytes, bitmap) in started {
        let pixels = match bitmap {
            Ok(bitmap) => match bitmap.await {
                Ok(bitmap) => reader.pixels(&bitmap.unchecked_into()),
                Err(e) => Err(js_error(e)),
            },
            Err(e) => Err(js_error(e)),
        };
        decoded.push((bytes, pixels));
    }
    Ok(decoded)
}

/// The browser's reason, as text.
fn js_error(e: JsValue) -> String {
    e.dyn_ref::<js_sys::Error>().map_or_else(|| format!("{e:?}"), |e| String::from(e.message()))
}

/// A WebGL2 context of its own that reads an image's pixels back.
struct Reader {
    gl: Gl,
}

impl Reader {
    fn new() -> Result<Self, String> {
        let canvas = web_sys::OffscreenCanvas::new(1, 1).map_err(js_error)?;
        let gl = canvas.get_context("webgl2").map_err(js_error)?.ok_or("cannot decode images: no WebGL2")?;
        let gl: Gl = gl.unchecked_into();
        gl.pixel_storei(Gl::UNPACK_PREMULTIPLY_ALPHA_WEBGL, 0);
        gl.pixel_storei(Gl::UNPACK_COLORSPACE_CONVERSION_WEBGL, Gl::NONE as i32);
        gl.pixel_storei(Gl::UNPACK_FLIP_Y_WEBGL, 0);
        Ok(Self { gl })
    }

    /// The bitmap's pixels: uploaded to a texture unchanged, the texture's row 0
    /// (the image's top row) is the first row `readPixels` returns.
    fn pixels(&self, bitmap: &web_sys::ImageBitmap) -> Decoded {
        let gl = &self.gl;
        let (w, h) = (bitmap.width(), bitmap.height());
        if w.max(h) > glint::asset::MAX_TEXTURE_SIDE {
            return Err(format!("it decodes to {w} x {h} pixels"));
        }
        let texture = gl.create_texture();
        let framebuffer = gl.create_framebuffer();
        gl.bind_texture(Gl::TEXTURE_2D, texture.as_ref());
        let uploaded = gl.tex_image_2d_with_u32_and_u32_and_image_bitmap(
            Gl::TEXTURE_2D,
            0,
            Gl::RGBA as i32,
            Gl::RGBA,
            Gl::UNSIGNED_BYTE,
            bitmap,
        );
        bitmap.close();
        gl.bind_framebuffer(Gl::FRAMEBUFFER, framebuffer.as_ref());
        gl.framebuffer_texture_2d(Gl::FRAMEBUFFER, Gl::COLOR_ATTACHMENT0, Gl::TEXTURE_2D, texture.as_ref(), 0);
        let mut pixels = vec![0; 4 * w as usize * h as usize];
        let read = uploaded.and_then(|()| {
            gl.read_pixels_with_opt_u8_array(0, 0, w as i32, h as i32, Gl::RGBA, Gl::UNSIGNED_BYTE, Some(&mut pixels))
        });
        gl.delete_framebuffer(framebuffer.as_ref());
        gl.delete_texture(texture.as_ref());
        match (read, gl.get_error()) {
            (Ok(()), Gl::NO_ERROR) => Ok((w, h, pixels)),
            (Err(e), _) => Err(js_error(e)),
            (Ok(()), error) => Err(format!("WebGL error {error:#x} reading its pixels")),
        }
    }
}
