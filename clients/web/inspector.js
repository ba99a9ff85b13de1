// The selection: an instance's document (id, mesh and its build options, material, transform,
// group path) or a group's (id, path, children), and the edits the viewer makes to it - move,
// rotate, scale, visibility, and an instance's colour - each one batch with If-Match on the
// version the panel was filled from. Each group in the path is a link that selects it. While the
// user types, a commit by someone else does not overwrite the fields: the panel notes it, and
// Apply then meets a 412.

const fmt = (v) => (Math.abs(v) < 1e-9 ? 0 : Number(v.toFixed(4)));

/// Translation, rotation (degrees, R = Rz Ry Rx as protocol/README "Transforms") and scale of a
/// row-major 4x4 affine transform without shear.
export function decompose(m) {
  const col = (j) => [m[j], m[4 + j], m[8 + j]];
  const len = (v) => Math.hypot(v[0], v[1], v[2]);
  const s = [len(col(0)), len(col(1)), len(col(2))];
  const r = (i, j) => m[4 * i + j] / (s[j] || 1);
  const ry = Math.asin(Math.max(-1, Math.min(1, -r(2, 0))));
  let rx, rz;
  if (Math.abs(Math.cos(ry)) > 1e-6) {
    rx = Math.atan2(r(2, 1), r(2, 2));
    rz = Math.atan2(r(1, 0), r(0, 0));
  } else {
    rx = Math.atan2(-r(1, 2), r(1, 1));
    rz = 0;
  }
  const deg = (a) => (a * 180) / Math.PI;
  return { translate: [m[3], m[7], m[11]], rotate_deg: [deg(rx), deg(ry), deg(rz)], scale: s };
}

/// What a mesh document holds, in words: "12 triangles", "300 points", "40 round bspline curve
/// segments in 10 strands", and its vertex keys when it deforms over the frame ("12 triangles,
/// 3 vertex keys").
export function meshPrimitives(m) {
  const keys = m.motion_keys > 1 ? `, ${m.motion_keys} vertex keys` : '';
  if (m.kind === 'points') return `${m.vertices} points${keys}`;
  if (m.kind === 'curves') {
    return `${m.primitives} ${m.style} ${m.basis} curve segments in ${m.strands} strands${keys}`;
  }
  return `${m.triangles} triangles${keys}`;
}

/// Where an object under a level-of-detail group is drawn, in words ("from 0 to 40", "from 40
/// on"), or '' for the full range (the default: drawn at every distance).
export function lodRange(d) {
  const near = d.lod_near || 0;
  const far = d.lod_far === undefined ? 1e15 : d.lod_far;
  if (near === 0 && far >= 1e15) return '';
  return far >= 1e15 ? `from ${fmt(near)} on` : `from ${fmt(near)} to ${fmt(far)}`;
}

/// An instance's animation in words: "3 keys from 0 to 1.5 s, looping"; '' without one.
export function animationSpan(d) {
  const keys = d.animation || [];
  if (!keys.length) return '';
  const span = keys.length === 1 ? `at ${fmt(keys[0].time)} s`
    : `from ${fmt(keys[0].time)} to ${fmt(keys[keys.length - 1].time)} s`;
  return `${keys.length} key${keys.length === 1 ? '' : 's'} ${span}` +
    (d.animation_loop ? ', looping' : '');
}

function hex(c) {
  const to = (v) => Math.round(Math.min(1, Math.max(0, v)) ** (1 / 2.2) * 255).toString(16).padStart(2, '0');
  return '#' + to(c[0]) + to(c[1]) + to(c[2]);
}

function unhex(h) {
  const v = (i) => (parseInt(h.slice(i, i + 2), 16) / 255) ** 2.2;
  return [Number(v(1).toFixed(4)), Number(v(3).toFixed(4)), Number(v(5).toFixed(4))];
}

export class Inspector {
  constructor(root, { applyEdit, onSelectGroup, onFrame }) {
    this.root = root;
    this.applyEdit = applyEdit;
    this.onSelectGroup = onSelectGroup;
    this.onFrame = onFrame;
    this.doc = null;
    this.dirty = false;
  }

  /// A new selection, or new values from the server (after a commit or a conflict).
  show(doc) {
    this.doc = doc;
    this.dirty = false;
    this.render();
  }

  /// The scene moved on (to `version`) while the user was typing: say so, keep the fields.
  outdated(version) {
    const note = this.root.querySelector('#sel-outdated');
    if (note) {
      note.hidden = false;
      note.textContent = `The scene changed (now version ${version}) since these values were ` +
        `read at version ${this.doc.version}; applying them will be refused as a conflict.`;
    }
  }

  edit(edits) {
    return this.applyEdit(edits, this.doc.version);
  }

  render() {
    const d = this.doc;
    const root = this.root;
    root.replaceChildren();
    root.classList.toggle('muted', !d);
    root.dataset.instance = d && d.kind === 'instance' ? d.id : '';
    root.dataset.group = d && d.kind === 'group' ? d.id : '';
    if (!d) {
      root.textContent = 'Nothing selected. Click the image to pick an instance.';
      return;
    }
    const t = decompose(d.transform);
    const table = document.createElement('table');
    const row = (k, v) => {
      const tr = table.insertRow();
      tr.insertCell().textContent = k;
      const cell = tr.insertCell();
      if (v instanceof Node) cell.append(v); else cell.textContent = v;
      return cell;
    };
    row('kind', d.kind);
    row('id', d.id).id = 'sel-id';
    if (d.name) row('name', d.name).id = 'sel-name';
    if (d.kind === 'instance') {
      row('mesh', d.mesh);
      if (d.mesh_doc) row('primitives', meshPrimitives(d.mesh_doc)).id = 'sel-primitives';
      if (d.motion && d.motion.length) row('motion', `${d.motion.length} keys`).id = 'sel-motion';
      const animated = animationSpan(d);
      if (animated) row('animation', animated).id = 'sel-animation';
      const b = d.mesh_build;
      if (b) {
        row('mesh build', `${b.prefer}, ${b.allow_refit ? 'refit' : 'no refit'}` +
          (b.compact ? ', compacted BLAS' : '')).id = 'sel-build';
      }
      row('material', d.material === null ? '(mesh default)' : d.material);
    }
    row(d.kind === 'group' ? 'parent path' : 'group path', this.pathLinks(d.path || [])).id = 'sel-path';
    if (d.kind === 'group') {
      row('children', `${d.children.groups} groups, ${d.children.instances} instances`);
      if (d.lod) row('level of detail', 'children are levels, chosen by distance').id = 'sel-lod';
    }
    const range = lodRange(d);
    if (range) row('LOD range', range).id = 'sel-lod-range';
    row('version', String(d.version)).id = 'sel-version';
    root.append(table);

    const vec = (name, values) => {
      const div = document.createElement('div');
      div.className = 'row';
      const label = document.createElement('span');
      label.textContent = name;
      label.style.width = '5em';
      div.append(label);
      values.forEach((v, i) => {
        const input = document.createElement('input');
        input.type = 'number';
        input.step = name === 'rotate' ? '5' : '0.1';
        input.value = fmt(v);
        input.id = `sel-${name}-${i}`;
        input.addEventListener('input', () => { this.dirty = true; });
        div.append(input);
      });
      root.append(div);
    };
    vec('translate', t.translate);
    vec('rotate', t.rotate_deg);
    vec('scale', t.scale);

    const note = document.createElement('div');
    note.id = 'sel-outdated';
    note.className = 'note';
    note.hidden = true;
    root.append(note);

    // Groups and instances take the same edits: set_transform with `group` or `instance`,
    // visibility through update_group or update_instance.
    const target = d.kind === 'group' ? { group: d.id } : { instance: d.id };
    const controls = document.createElement('div');
    controls.className = 'row';
    const apply = document.createElement('button');
    apply.textContent = 'Apply transform';
    apply.id = 'sel-apply';
    apply.onclick = () => {
      const read = (name) => [0, 1, 2].map((i) => Number(root.querySelector(`#sel-${name}-${i}`).value));
      this.edit([{ op: 'set_transform', ...target,
        transform: { translate: read('translate'), rotate_deg: read('rotate'), scale: read('scale') } }]);
    };
    const visible = document.createElement('label');
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.checked = d.visible;
    box.id = 'sel-visible';
    box.onchange = () => this.edit([{ op: d.kind === 'group' ? 'update_group' : 'update_instance', ...target,
      visible: box.checked }]);
    visible.append(box, ' visible');
    // Aims the viewer's camera at the selection's world bounds (a group's: its whole subtree).
    const frame = document.createElement('button');
    frame.textContent = 'Frame';
    frame.id = 'sel-frame';
    frame.disabled = !d.bounds;
    frame.onclick = () => this.onFrame(d.bounds);
    controls.append(apply, frame, visible);
    root.append(controls);
    if (d.kind === 'instance') this.colorRow(d);
  }

  /// "/a/b" with each group a link that selects it; "(root)" when empty.
  pathLinks(path) {
    const span = document.createElement('span');
    if (!path.length) {
      span.textContent = '(root)';
      return span;
    }
    path.forEach((g) => {
      span.append('/');
      const link = document.createElement('button');
      link.className = 'path-link';
      link.textContent = g;
      link.dataset.group = g;
      link.title = `select group '${g}'`;
      link.onclick = () => this.onSelectGroup(g);
      span.append(link);
    });
    return span;
  }

  // Colour: the instance gets a material of its own ("<id>.color") the first time, so the
  // change never repaints other instances sharing a material.
  colorRow(d) {
    const colorRow = document.createElement('div');
    colorRow.className = 'row';
    const color = document.createElement('input');
    color.type = 'color';
    color.id = 'sel-color';
    color.value = hex(d.resolved_material.base_color);
    color.onchange = () => {
      const own = d.id + '.color';
      const base = unhex(color.value);
      const m = d.resolved_material;
      const edits = d.material === own
        ? [{ op: 'update_material', material: own, base_color: base }]
        : [{ op: 'add_material', ...m, id: own, base_color: base },
           { op: 'update_instance', instance: d.id, material: own }];
      this.edit(edits);
    };
    const colorLabel = document.createElement('span');
    colorLabel.textContent = 'colour';
    colorLabel.style.width = '5em';
    colorRow.append(colorLabel, color);
    this.root.append(colorRow);
  }
}
