//! Camera input: one camera model steered two ways. Flying moves the eye (WASD, Q/E down and
//! up, shift faster) and turns it around itself (mouse with the right button held);
//! orbiting turns it around the point it looks at (mouse with the left button held) and the
//! wheel moves it towards or away from that point. Keys that change settings come back as
//! [`Action`]s.

use caveclod_core::glam::{Vec2, Vec3};
use caveclod_core::LookAt;
use winit::event::{ElementState, MouseButton, MouseScrollDelta};
use winit::keyboard::KeyCode;

/// Radians per pixel of mouse movement.
const TURN_PER_PIXEL: f32 = 0.005;
/// Pitch stays short of straight up or down, where the view's up vector degenerates.
const MAX_PITCH: f32 = 1.5;

/// A camera as eye, heading and the distance to the point it looks at.
#[derive(Clone, Copy, Debug)]
pub struct CameraControl {
    pub eye: Vec3,
    /// Heading around +y, radians (0 looks along +z).
    yaw: f32,
    /// Elevation of the view direction, radians.
    pitch: f32,
    /// Distance from the eye to the point looked at (the orbit centre).
    distance: f32,
    fov_y: f32,
    /// The scene's centre and radius: flying speed and clip planes follow them.
    centre: Vec3,
    radius: f32,
    /// Seconds of animation so far (each camera starts at its own phase).
    phase: f32,
    /// The distance the animation breathes around.
    base_distance: f32,
}

impl CameraControl {
    /// The control that sees `look`; camera `index` of the scene (centre, radius).
    pub fn from_look(look: &LookAt, centre: Vec3, radius: f32, index: usize) -> Self {
        let to = look.target - look.eye;
        let distance = to.length().max(1e-6);
        let f = to / distance;
        Self {
            eye: look.eye,
            yaw: f.x.atan2(f.z),
            pitch: f.y.clamp(-1.0, 1.0).asin(),
            distance,
            fov_y: look.fov_y,
            centre,
            radius,
            phase: index as f32 * 1.7,
            base_distance: distance,
        }
    }

    fn forward(&self) -> Vec3 {
        Vec3::new(
            self.pitch.cos() * self.yaw.sin(),
            self.pitch.sin(),
            self.pitch.cos() * self.yaw.cos(),
        )
    }

    fn target(&self) -> Vec3 {
        self.eye + self.forward() * self.distance
    }

    /// The view: near plane a thousandth of the scene's radius, far plane beyond its far
    /// side.
    pub fn look(&self) -> LookAt {
        LookAt {
            eye: self.eye,
            target: self.target(),
            up: Vec3::Y,
            fov_y: self.fov_y,
            near: self.radius * 1e-3,
            far: (self.eye - self.centre).length() + 2.0 * self.radius,
        }
    }

    /// Moves the eye by `step` in view-relative axes (x right, y up, z forward).
    fn fly(&mut self, step: Vec3) {
        let f = self.forward();
        let right = f.cross(Vec3::Y).normalize_or_zero();
        self.eye += right * step.x + Vec3::Y * step.y + f * step.z;
    }

    /// Turns the view around the eye.
    fn turn(&mut self, pixels: Vec2) {
        self.yaw -= pixels.x * TURN_PER_PIXEL;
        self.pitch = (self.pitch - pixels.y * TURN_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Turns the eye around the point looked at.
    fn orbit(&mut self, pixels: Vec2) {
        let target = self.target();
        self.turn(-pixels);
        self.eye = target - self.forward() * self.distance;
    }

    /// Moves towards (`steps > 0`) or away from the point looked at, a tenth of the way a
    /// step.
    fn zoom(&mut self, steps: f32) {
        let target = self.target();
        let min = self.radius * 1e-3;
        self.distance = (self.distance * 0.9f32.powf(steps)).max(min);
        self.eye = target - self.forward() * self.distance;
    }

    /// An animated camera orbits its point slowly while its distance breathes in and out,
    /// so its front both refines and coarsens.
    pub fn animate(&mut self, dt: f32) {
        self.phase += dt;
        let target = self.target();
        self.yaw += 0.35 * dt;
        self.distance = self.base_distance * (0.6 + 0.15 * (0.6 * self.phase).sin());
        self.eye = target - self.forward() * self.distance;
    }
}

/// A key that changes a setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Steer camera `n` (0-based).
    Select(usize),
    /// Tolerance up (coarser) or down (finer).
    Coarser,
    Finer,
    Wireframe,
    CycleColour,
    /// Geomorphs in the vertex stage, in the compute stage, or off.
    CycleMorphs,
    Freeze,
    Quit,
}

/// Keys and buttons held, and the mouse movement and wheel steps not yet applied.
#[derive(Default)]
pub struct Input {
    forward: bool,
    back: bool,
    left: bool,
    right: bool,
    down: bool,
    up: bool,
    fast: bool,
    looking: bool,
    orbiting: bool,
    cursor: Option<Vec2>,
    turn: Vec2,
    orbit: Vec2,
    wheel: f32,
}

impl Input {
    /// Records a key; returns the action of a pressed setting key.
    pub fn key(&mut self, code: KeyCode, state: ElementState) -> Option<Action> {
        let down = state == ElementState::Pressed;
        match code {
            KeyCode::KeyW => self.forward = down,
            KeyCode::KeyS => self.back = down,
            KeyCode::KeyA => self.left = down,
            KeyCode::KeyD => self.right = down,
            KeyCode::KeyQ => self.down = down,
            KeyCode::KeyE => self.up = down,
            KeyCode::ShiftLeft | KeyCode::ShiftRight => self.fast = down,
            _ if down => return action(code),
            _ => {}
        }
        None
    }

    pub fn button(&mut self, button: MouseButton, state: ElementState) {
        let down = state == ElementState::Pressed;
        match button {
            MouseButton::Right => self.looking = down,
            MouseButton::Left => self.orbiting = down,
            _ => {}
        }
    }

    /// Records the cursor position; while a button is held, the movement turns or orbits.
    pub fn cursor(&mut self, at: Vec2) {
        if let Some(last) = self.cursor {
            let d = at - last;
            if self.looking {
                self.turn += d;
            } else if self.orbiting {
                self.orbit += d;
            }
        }
        self.cursor = Some(at);
    }

    pub fn wheel(&mut self, delta: MouseScrollDelta) {
        self.wheel += match delta {
            MouseScrollDelta::LineDelta(_, y) => y,
            MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
        };
    }

    /// Lets go of everything held (the window lost focus).
    pub fn release_all(&mut self) {
        *self = Self {
            cursor: self.cursor,
            ..Self::default()
        };
    }

    /// `true` if something is held or waiting to be applied.
    pub fn active(&self) -> bool {
        self.forward
            || self.back
            || self.left
            || self.right
            || self.down
            || self.up
            || self.turn != Vec2::ZERO
            || self.orbit != Vec2::ZERO
            || self.wheel != 0.0
    }

    /// Applies `dt` seconds of the keys held and the movement since the last call to `c`.
    pub fn steer(&mut self, c: &mut CameraControl, dt: f32) {
        let axis = |plus: bool, minus: bool| f32::from(u8::from(plus)) - f32::from(u8::from(minus));
        let dir = Vec3::new(
            axis(self.right, self.left),
            axis(self.up, self.down),
            axis(self.forward, self.back),
        );
        let speed = c.radius * if self.fast { 1.5 } else { 0.3 };
        c.fly(dir * speed * dt);
        c.turn(std::mem::take(&mut self.turn));
        c.orbit(std::mem::take(&mut self.orbit));
        c.zoom(std::mem::take(&mut self.wheel));
    }
}

/// The setting a pressed key changes.
fn action(code: KeyCode) -> Option<Action> {
    Some(match code {
        KeyCode::Digit1 | KeyCode::Numpad1 => Action::Select(0),
        KeyCode::Digit2 | KeyCode::Numpad2 => Action::Select(1),
        KeyCode::Digit3 | KeyCode::Numpad3 => Action::Select(2),
        KeyCode::Digit4 | KeyCode::Numpad4 => Action::Select(3),
        KeyCode::Equal | KeyCode::NumpadAdd => Action::Coarser,
        KeyCode::Minus | KeyCode::NumpadSubtract => Action::Finer,
        KeyCode::KeyZ => Action::Wireframe,
        KeyCode::KeyC => Action::CycleColour,
        KeyCode::KeyG => Action::CycleMorphs,
        KeyCode::KeyF | KeyCode::Space => Action::Freeze,
        KeyCode::Escape => Action::Quit,
        _ => return None,
    })
}

/// The keys, for the panel.
pub const KEY_HELP: &[(&str, &str)] = &[
    ("W A S D", "fly forward / left / back / right"),
    ("Q / E", "fly down / up"),
    ("Shift", "fly faster"),
    ("right drag", "look around"),
    ("left drag", "orbit the point looked at"),
    ("wheel", "zoom towards it"),
    ("1-4", "steer camera 1-4"),
    ("+ / -", "tolerance coarser / finer"),
    ("Z", "wireframe"),
    ("C", "colour by surface / depth"),
    ("G", "geomorphs: vertex stage / compute stage / off"),
    ("F, Space", "freeze the steered camera's front"),
    ("Esc", "quit"),
];
