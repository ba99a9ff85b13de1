// The viewer's own camera: orbit, pan, zoom and fly with mouse, touch and keyboard. It starts
// as a copy of the scene camera and is sent as the stream's camera override; "follow" drops it.

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const len = (a) => Math.sqrt(dot(a, a));
const norm = (a) => scale(a, 1 / (len(a) || 1));

/// The camera's basis as the engine builds it (engine/render/camera_rays.h).
export function basis(cam) {
  const forward = norm(sub(cam.target, cam.eye));
  const right = norm(cross(forward, cam.up));
  const up = cross(right, forward);
  return { forward, right, up };
}

/// Pixel position of world point `p` in a width x height frame, or null behind the camera.
export function project(cam, p, width, height) {
  const { forward, right, up } = basis(cam);
  const d = sub(p, cam.eye);
  const z = dot(d, forward);
  if (z <= 1e-6) return null;
  const tanHalf = Math.tan((cam.fov_y_deg * Math.PI) / 360);
  const aspect = width / height;
  const x = dot(d, right) / z / (tanHalf * aspect);
  const y = dot(d, up) / z / tanHalf;
  return [(x * 0.5 + 0.5) * width, (0.5 - y * 0.5) * height];
}

export class CameraControl {
  /// `element` gets the pointer and key handlers; `onChange(camera)` runs after each move, and
  /// `onClick(x, y)` for a click that did not drag (element pixels).
  constructor(element, { onChange, onClick, getSceneCamera }) {
    this.el = element;
    this.onChange = onChange;
    this.onClick = onClick;
    this.getSceneCamera = getSceneCamera;
    this.camera = null;  // null: following the scene camera
    this.pointers = new Map();
    this.dragged = 0;
    this.keys = new Set();
    this.bind();
  }

  /// The override to edit: the current one, or a copy of the scene camera.
  current() {
    if (!this.camera) {
      const s = this.getSceneCamera();
      if (!s) return null;
      this.camera = { eye: [...s.eye], target: [...s.target], up: [...s.up], fov_y_deg: s.fov_y_deg };
    }
    return this.camera;
  }

  follow() {
    this.camera = null;
    this.onChange(null);
  }

  /// Aims at `bounds` ({min, max}, world) as a render's `frame` does (protocol/framing.h): the
  /// same viewing direction, the eye back until the box's bounding sphere fits the narrower
  /// field of view of a frame `aspect` (width / height) wide.
  frame(bounds, aspect) {
    const c = this.current();
    if (!c || !bounds) return;
    const center = scale(add(bounds.min, bounds.max), 0.5);
    const radius = Math.max(0.5 * len(sub(bounds.max, bounds.min)), 1e-3);
    const halfV = (c.fov_y_deg * Math.PI) / 360;
    const half = Math.min(halfV, Math.atan(Math.tan(halfV) * aspect));
    const forward = norm(sub(c.target, c.eye));
    c.target = center;
    c.eye = sub(center, scale(forward, (1.05 * radius) / Math.sin(half)));
    this.onChange(c);
  }

  orbit(dx, dy) {
    const c = this.current();
    if (!c) return;
    const worldUp = norm(c.up);
    let off = sub(c.eye, c.target);
    const r = len(off);
    // Yaw about the camera's up axis, pitch about its right axis, kept off the poles.
    off = rotate(off, worldUp, -dx * 0.008);
    const right = norm(cross(norm(scale(off, -1)), worldUp));
    const pitched = rotate(off, right, -dy * 0.008);
    const cosUp = dot(norm(pitched), worldUp);
    if (Math.abs(cosUp) < 0.995) off = pitched;
    c.eye = add(c.target, scale(norm(off), r));
    this.onChange(c);
  }

  pan(dx, dy) {
    const c = this.current();
    if (!c) return;
    const { right, up } = basis(c);
    const k = len(sub(c.eye, c.target)) * 0.0015;
    const move = add(scale(right, -dx * k), scale(up, dy * k));
    c.eye = add(c.eye, move);
    c.target = add(c.target, move);
    this.onChange(c);
  }

  zoom(factor) {
    const c = this.current();
    if (!c) return;
    const off = sub(c.eye, c.target);
    const r = Math.min(Math.max(len(off) * factor, 0.05), 1e5);
    c.eye = add(c.target, scale(norm(off), r));
    this.onChange(c);
  }

  fly(forwardAmount, rightAmount, upAmount) {
    const c = this.current();
    if (!c) return;
    const { forward, right } = basis(c);
    const step = Math.max(len(sub(c.eye, c.target)) * 0.03, 0.05);
    const move = add(add(scale(forward, forwardAmount * step), scale(right, rightAmount * step)),
                     scale(norm(c.up), upAmount * step));
    c.eye = add(c.eye, move);
    c.target = add(c.target, move);
    this.onChange(c);
  }

  bind() {
    const el = this.el;
    el.addEventListener('contextmenu', (e) => e.preventDefault());
    el.addEventListener('pointerdown', (e) => {
      el.setPointerCapture(e.pointerId);
      this.pointers.set(e.pointerId, { x: e.clientX, y: e.clientY, button: e.button, shift: e.shiftKey });
      this.dragged = 0;
      el.focus();
    });
    el.addEventListener('pointermove', (e) => {
      const p = this.pointers.get(e.pointerId);
      if (!p) return;
      const dx = e.clientX - p.x, dy = e.clientY - p.y;
      p.x = e.clientX; p.y = e.clientY;
      this.dragged += Math.abs(dx) + Math.abs(dy);
      if (this.dragged < 4) return;
      if (this.pointers.size === 2) {
        // Two fingers: pinch zooms, moving together pans.
        const [a, b] = [...this.pointers.values()];
        const dist = Math.hypot(a.x - b.x, a.y - b.y);
        if (this.pinch) this.zoom(this.pinch / (dist || 1));
        this.pinch = dist;
        this.pan(dx / 2, dy / 2);
      } else if (p.button === 2 || p.button === 1 || p.shift) {
        this.pan(dx, dy);
      } else {
        this.orbit(dx, dy);
      }
    });
    const up = (e) => {
      const p = this.pointers.get(e.pointerId);
      this.pointers.delete(e.pointerId);
      if (this.pointers.size < 2) this.pinch = null;
      if (p && this.dragged < 4 && p.button === 0 && e.type === 'pointerup') {
        const r = el.getBoundingClientRect();
        this.onClick(e.clientX - r.left, e.clientY - r.top);
      }
    };
    el.addEventListener('pointerup', up);
    el.addEventListener('pointercancel', up);
    el.addEventListener('wheel', (e) => {
      e.preventDefault();
      this.zoom(Math.exp(e.deltaY * 0.001));
    }, { passive: false });
    el.addEventListener('keydown', (e) => {
      const k = e.key.toLowerCase();
      const moves = {
        w: [1, 0, 0], s: [-1, 0, 0], a: [0, -1, 0], d: [0, 1, 0], q: [0, 0, -1], e: [0, 0, 1],
      };
      if (moves[k]) this.fly(...moves[k]);
      else if (k === 'arrowleft') this.orbit(-20, 0);
      else if (k === 'arrowright') this.orbit(20, 0);
      else if (k === 'arrowup') this.orbit(0, -20);
      else if (k === 'arrowdown') this.orbit(0, 20);
      else if (k === '+' || k === '=') this.zoom(0.9);
      else if (k === '-') this.zoom(1.1);
      else if (k === 'f') this.follow();
      else return;
      e.preventDefault();
    });
  }
}

/// `v` rotated by `angle` radians about unit axis `k` (Rodrigues).
function rotate(v, k, angle) {
  const c = Math.cos(angle), s = Math.sin(angle);
  return add(add(scale(v, c), scale(cross(k, v), s)), scale(k, dot(k, v) * (1 - c)));
}
