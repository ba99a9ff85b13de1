// The selected instance: its document (id, mesh, material, transform, group path) and the edits
// the viewer makes to it - move, rotate, scale, visibility, colour - each one batch with
// If-Match on the version the panel was filled from.

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

function hex(c) {
  const to = (v) => Math.round(Math.min(1, Math.max(0, v)) ** (1 / 2.2) * 255).toString(16).padStart(2, '0');
  return '#' + to(c[0]) + to(c[1]) + to(c[2]);
}

function unhex(h) {
  const v = (i) => (parseInt(h.slice(i, i + 2), 16) / 255) ** 2.2;
  return [Number(v(1).toFixed(4)), Number(v(3).toFixed(4)), Number(v(5).toFixed(4))];
}

export class Inspector {
  constructor(root, { applyEdit }) {
    this.root = root;
    this.applyEdit = applyEdit;
    this.doc = null;
    this.hit = null;
  }

  show(doc, hit) {
    this.doc = doc;
    this.hit = hit || null;
    this.render();
  }

  /// New values from the server (after a commit or a conflict).
  refresh(doc) {
    this.doc = doc;
    this.render();
  }

  render() {
    const d = this.doc;
    const root = this.root;
    root.replaceChildren();
    root.classList.toggle('muted', !d);
    if (!d) {
      root.textContent = 'Nothing selected. Click the image to pick an instance.';
      root.dataset.instance = '';
      return;
    }
    root.dataset.instance = d.id;
    const t = decompose(d.transform);
    const path = this.hit ? this.hit.group_path : d.parent ? [d.parent] : [];
    const table = document.createElement('table');
    const row = (k, v) => {
      const tr = table.insertRow();
      tr.insertCell().textContent = k;
      const cell = tr.insertCell();
      if (v instanceof Node) cell.append(v); else cell.textContent = v;
      return cell;
    };
    row('id', d.id).id = 'sel-id';
    row('mesh', d.mesh);
    row('material', d.material === null ? '(mesh default)' : d.material);
    row('group path', path.length ? '/' + path.join('/') : '(root)');
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
        div.append(input);
      });
      root.append(div);
    };
    vec('translate', t.translate);
    vec('rotate', t.rotate_deg);
    vec('scale', t.scale);

    const controls = document.createElement('div');
    controls.className = 'row';
    const apply = document.createElement('button');
    apply.textContent = 'Apply transform';
    apply.id = 'sel-apply';
    apply.onclick = () => {
      const read = (name) => [0, 1, 2].map((i) => Number(root.querySelector(`#sel-${name}-${i}`).value));
      this.applyEdit([{ op: 'set_transform', instance: d.id,
        transform: { translate: read('translate'), rotate_deg: read('rotate'), scale: read('scale') } }], d.version);
    };
    const visible = document.createElement('label');
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.checked = d.visible;
    box.id = 'sel-visible';
    box.onchange = () => this.applyEdit([{ op: 'update_instance', instance: d.id, visible: box.checked }], d.version);
    visible.append(box, ' visible');
    controls.append(apply, visible);
    root.append(controls);

    // Colour: the instance gets a material of its own ("<id>.color") the first time, so the
    // change never repaints other instances sharing a material.
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
        : [{ op: 'add_material', id: own, base_color: base, roughness: m.roughness, metallic: m.metallic,
             emission: m.emission },
           { op: 'update_instance', instance: d.id, material: own }];
      this.applyEdit(edits, d.version);
    };
    const colorLabel = document.createElement('span');
    colorLabel.textContent = 'colour';
    colorLabel.style.width = '5em';
    colorRow.append(colorLabel, color);
    root.append(colorRow);
  }
}
