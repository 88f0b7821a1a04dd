//! Scripted input (`view --frames N --keys ...`): one entry per frame from the first — a key,
//! or a click on the part panel at a window pixel (`click:X:Y`, pressed in its frame and
//! released in the next, through egui as a mouse click is), or a panel setting set directly
//! (`part:N` shows / hides instance N as its checkbox does, `explode:F` puts the explode
//! slider at F in [0, 1]).

use winit::keyboard::{Key, NamedKey};

/// One scripted entry.
#[derive(Clone, Debug, PartialEq)]
pub enum Scripted {
    Key(Key),
    /// A left click at window pixel (x, y), given to the panel's egui.
    Click(f32, f32),
    /// Instance N shown / hidden (the panel's checkbox).
    Part(usize),
    /// The explode slider's position.
    Explode(f64),
}

/// The key a script name stands for: a character (`b`, `w`, `+`…) or `left`, `right`, `up`,
/// `down`, `pageup`, `pagedown`, `escape`.
pub fn script_key(name: &str) -> Option<Key> {
    Some(match name {
        "left" => Key::Named(NamedKey::ArrowLeft),
        "right" => Key::Named(NamedKey::ArrowRight),
        "up" => Key::Named(NamedKey::ArrowUp),
        "down" => Key::Named(NamedKey::ArrowDown),
        "pageup" => Key::Named(NamedKey::PageUp),
        "pagedown" => Key::Named(NamedKey::PageDown),
        "escape" => Key::Named(NamedKey::Escape),
        "space" => Key::Named(NamedKey::Space),
        c if c.chars().count() == 1 => Key::Character(c.into()),
        _ => return None,
    })
}

/// A script entry: a key name ([`script_key`]), `click:X:Y`, `part:N` or `explode:F`.
pub fn script_input(name: &str) -> Option<Scripted> {
    if let Some(at) = name.strip_prefix("click:") {
        let (x, y) = at.split_once(':')?;
        let (x, y) = (x.parse::<f32>().ok()?, y.parse::<f32>().ok()?);
        return (x.is_finite() && y.is_finite()).then_some(Scripted::Click(x, y));
    }
    if let Some(n) = name.strip_prefix("part:") {
        return n.parse().ok().map(Scripted::Part);
    }
    if let Some(f) = name.strip_prefix("explode:") {
        let f = f.parse::<f64>().ok()?;
        return (0.0..=1.0).contains(&f).then_some(Scripted::Explode(f));
    }
    script_key(name).map(Scripted::Key)
}
