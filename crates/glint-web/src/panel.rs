//! The scene's controls as HTML beside the canvas (`#controls`): the list the
//! viewer draws with egui ([`glint::world::Controls::list`]), one `<fieldset>`
//! a section and one input a control (a checkbox, a range with its value, a
//! select, a button), each carrying `data-control` with the control's id. A
//! change goes to [`Controls::set`](glint::world::Controls::set); the panel is
//! built again when a scene is shown or the list itself changes (a time of
//! day appears). `H` hides it.

use crate::{Shown, Viewer};
use glint::world::{Control, ControlKind};
use std::cell::RefCell;
use std::rc::Rc;
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

/// Fill `#controls` with the shown scene's controls (empty without a scene).
pub fn build(viewer: &Rc<RefCell<Viewer>>) -> Result<(), String> {
    let document = web_sys::window().and_then(|w| w.document()).ok_or("no document")?;
    let Some(panel) = document.get_element_by_id("controls") else { return Ok(()) };
    panel.set_inner_html("");
    let list = viewer.borrow().shown.as_ref().map(|s| s.controls.list()).unwrap_or_default();
    for section in list.chunk_by(|a, b| a.section == b.section) {
        let fieldset = element(&document, "fieldset")?;
        let legend = element(&document, "legend")?;
        legend.set_text_content(Some(&section[0].section));
        append(&fieldset, &legend)?;
        for control in section {
            append(&fieldset, &input(&document, viewer, control)?)?;
        }
        append(&panel, &fieldset)?;
    }
    Ok(())
}

/// One control: a `<label>` holding its input.
fn input(
    document: &web_sys::Document,
    viewer: &Rc<RefCell<Viewer>>,
    control: &Control,
) -> Result<web_sys::Element, String> {
    let label = element(document, "label")?;
    let field = match &control.kind {
        ControlKind::Toggle { on } => {
            let e = element(document, "input")?;
            attribute(&e, "type", "checkbox")?;
            set(&e, "checked", JsValue::from_bool(*on))?;
            e
        }
        ControlKind::Slider { value, min, max, step } => {
            let e = element(document, "input")?;
            for (name, v) in [
                ("type", "range".to_owned()),
                ("min", min.to_string()),
                ("max", max.to_string()),
                ("step", step.to_string()),
                ("value", value.to_string()),
            ] {
                attribute(&e, name, &v)?;
            }
            e
        }
        ControlKind::Choice { index, options } => {
            let e = element(document, "select")?;
            for (k, option) in options.iter().enumerate() {
                let o = element(document, "option")?;
                attribute(&o, "value", &k.to_string())?;
                o.set_text_content(Some(option));
                if k == *index {
                    attribute(&o, "selected", "")?;
                }
                append(&e, &o)?;
            }
            e
        }
        ControlKind::Button => {
            let e = element(document, "button")?;
            e.set_text_content(Some(&control.label));
            e
        }
    };
    attribute(&field, "data-control", &control.id)?;
    append(&label, &field)?;
    if !matches!(control.kind, ControlKind::Button) {
        let text = element(document, "span")?;
        let value = match &control.kind {
            ControlKind::Slider { value, .. } => format!(" {} {value:.2}", control.label),
            _ => format!(" {}", control.label),
        };
        text.set_text_content(Some(&value));
        append(&label, &text)?;
    }
    listen(viewer, &field, control)?;
    Ok(label)
}

/// Send the input's changes to the controls, rebuilding the panel when the
/// list changes (and a slider's shown value).
fn listen(viewer: &Rc<RefCell<Viewer>>, field: &web_sys::Element, control: &Control) -> Result<(), String> {
    let (viewer, id, kind, label) = (viewer.clone(), control.id.clone(), control.kind.clone(), control.label.clone());
    let target = field.clone();
    let on_change = Closure::<dyn FnMut(web_sys::Event)>::new(move |_: web_sys::Event| {
        let value = match kind {
            ControlKind::Toggle { .. } => get(&target, "checked").as_bool().map(|on| f32::from(u8::from(on))),
            ControlKind::Button => Some(1.0),
            _ => get(&target, "value").as_string().and_then(|v| v.parse::<f32>().ok()),
        };
        let Some(value) = value else { return };
        let changed = {
            let mut v = viewer.borrow_mut();
            let Some(Shown { controls, .. }) = v.shown.as_mut() else { return };
            let before: Vec<String> = controls.list().into_iter().map(|c| c.id).collect();
            if let Err(e) = controls.set(&id, value) {
                web_sys::console::warn_1(&e.into());
            }
            let after: Vec<String> = controls.list().into_iter().map(|c| c.id).collect();
            before != after
        };
        if changed {
            if let Err(e) = build(&viewer) {
                web_sys::console::warn_1(&e.into());
            }
        } else if let (ControlKind::Slider { .. }, Some(text)) = (&kind, target.next_element_sibling()) {
            text.set_text_content(Some(&format!(" {label} {value:.2}")));
        }
    });
    let event = match control.kind {
        ControlKind::Button => "click",
        ControlKind::Slider { .. } => "input",
        _ => "change",
    };
    let added = field.add_event_listener_with_callback(event, on_change.as_ref().unchecked_ref());
    on_change.forget();
    added.map_err(|e| format!("{e:?}"))
}

/// Show or hide the panel (`H`).
pub fn toggle() {
    let panel = web_sys::window().and_then(|w| w.document()).and_then(|d| d.get_element_by_id("controls"));
    if let Some(panel) = panel {
        let _ = panel.toggle_attribute("hidden");
    }
}

fn element(document: &web_sys::Document, name: &str) -> Result<web_sys::Element, String> {
    document.create_element(name).map_err(|e| format!("{e:?}"))
}

fn append(parent: &web_sys::Element, child: &web_sys::Element) -> Result<(), String> {
    parent.append_child(child).map(drop).map_err(|e| format!("{e:?}"))
}

fn attribute(e: &web_sys::Element, name: &str, value: &str) -> Result<(), String> {
    e.set_attribute(name, value).map_err(|e| format!("{e:?}"))
}

fn set(e: &web_sys::Element, name: &str, value: JsValue) -> Result<(), String> {
    js_sys::Reflect::set(e, &name.into(), &value).map(drop).map_err(|e| format!("{e:?}"))
}

fn get(e: &web_sys::Element, name: &str) -> JsValue {
    js_sys::Reflect::get(e, &name.into()).unwrap_or(JsValue::UNDEFINED)
}
