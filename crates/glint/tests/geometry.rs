//! The geometry path: the mesh pool's pages keep every shape intact as they grow,
//! and vertex colours select their own vertex layout and shader variant.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::ShapeKind;
use glint::scene::ShadingModel;
use glint::{Camera, Entity, FrameStats, Gpu, Material, OffscreenTarget, Renderer};

/// Render `entities` once at 32×32 from the front, unlit; returns the image and stats.
fn render(r: &mut Renderer, gpu: &Gpu, entities: &[&Entity]) -> (image::RgbaImage, FrameStats) {
    let camera = Camera::perspective(50.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO);
    let mut target = OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
    for e in entities {
        r.submit(e);
    }
    let stats = r.flush(camera, &[], &glint::Shadows::none(), &mut target).expect("frame");
    (target.read_rgba8(gpu).expect("readback"), stats)
}

fn unlit() -> Material {
    Material { shading: ShadingModel::Unlit, ..Material::color("white", 1.0, 1.0, 1.0) }
}

#[test]
fn growing_pool_pages_keep_earlier_shapes_intact() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let m = r.add_material(unlit());
    let first = r.add_shape(ShapeKind::Torus.mesh());
    let torus = Entity::new(first, m, Mat4::IDENTITY);
    let (before, _) = render(&mut r, gpu, &[&torus]);
    // Twelve blobs of ~7,400 vertices (~350 KB each) overflow the first 1 MiB page
    // several times over: each growth copies what the page held.
    let blobs: Vec<Entity> = (0..12)
        .map(|seed| {
            let shape = r.add_shape(ShapeKind::Blob { detail: 86, seed }.mesh());
            Entity::new(shape, m, Mat4::from_translation(Vec3::new(0.0, 0.0, -50.0)))
        })
        .collect();
    let refs: Vec<&Entity> = blobs.iter().chain([&torus]).collect();
    let (_, grown) = render(&mut r, gpu, &refs);
    assert!(grown.bytes_uploaded.meshes > 12 * 300_000, "{}", grown.bytes_uploaded.meshes);
    let (after, _) = render(&mut r, gpu, &[&torus]);
    assert!(before.pixels().any(|p| p.0 == [255, 255, 255, 255]), "the torus is in view");
    assert_eq!(before, after, "the first shape reads the same after its page grew");
}

#[test]
fn vertex_colours_tint_the_base_colour_in_their_own_variant() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    // The draws counted below are the two shapes' at full detail (a level of
    // detail the GPU picks is a draw of its own).
    r.set_levels_of_detail(false);
    let m = r.add_material(unlit());
    // A 10×10 grid, so colours change only across the middle column of quads.
    let plane = glint::asset::procedural::plane(10);
    // Red on the left half (x < 0), blue on the right.
    let colors =
        plane.vertices().iter().map(|v| if v.position[0] < 0.0 { [1.0, 0.0, 0.0, 1.0] } else { [0.0, 0.0, 1.0, 1.0] });
    let colored = plane.clone().with_colors(colors.collect()).expect("one colour per vertex");
    assert!(plane.clone().with_colors(vec![[1.0; 4]]).is_err(), "a colour per vertex, no fewer");
    let (plain, colored) = (r.add_shape(plane), r.add_shape(colored));
    // The plane lies in XZ facing +Y: stand it up to face the camera.
    let up = Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2);
    let e = Entity::new(colored, m, up);
    let (image, stats) = render(&mut r, gpu, &[&e]);
    assert_eq!(stats.pipelines_compiled, 1);
    let left = image.get_pixel(11, 16).0;
    let right = image.get_pixel(20, 16).0;
    assert!(left[0] > 200 && left[2] < 60, "left is red: {left:?}");
    assert!(right[2] > 200 && right[0] < 60, "right is blue: {right:?}");
    // The same material on an uncoloured mesh is another variant (and layout): white.
    let white = Entity::new(plain, m, up);
    let (image, stats) = render(&mut r, gpu, &[&white]);
    assert_eq!(stats.pipelines_compiled, 1, "the colourless variant");
    assert_eq!(image.get_pixel(10, 16).0, [255, 255, 255, 255]);
    // Both together: two pipelines (bound again in occlusion culling's second
    // pass), two pool pages, nothing new compiled.
    let (_, stats) = render(&mut r, gpu, &[&e, &white]);
    let passes = if stats.occlusion { 2 } else { 1 };
    assert_eq!((stats.pipelines_compiled, stats.pipelines_bound, stats.draws), (0, 2 * passes, 2));
}
