// The scene panel: instances from the paginated listing (GET /v1/scene/instances), searchable
// by id (filtered as pages arrive), a click selects.

import { api } from './api.js';

const PAGE = 200;

export class ScenePanel {
  constructor(list, search, more, { onSelect }) {
    this.list = list;
    this.search = search;
    this.more = more;
    this.onSelect = onSelect;
    this.items = [];
    this.cursor = null;
    this.selected = null;
    let timer = null;
    search.addEventListener('input', () => {
      clearTimeout(timer);
      timer = setTimeout(() => this.render(), 100);
    });
    more.addEventListener('click', () => this.page());
  }

  async load() {
    this.items = [];
    this.cursor = null;
    await this.page();
  }

  async page() {
    const q = new URLSearchParams({ limit: PAGE });
    if (this.cursor) q.set('cursor', this.cursor);
    try {
      const { doc } = await api('/v1/scene/instances?' + q);
      this.items.push(...doc.items.map((i) => ({ id: i.id, mesh: i.mesh, visible: i.world_visible })));
      this.cursor = doc.next_cursor;
    } catch (e) {
      this.cursor = null;
      this.list.textContent = 'Cannot list instances: ' + e.message;
      return;
    }
    this.render();
  }

  mark(id) {
    this.selected = id;
    for (const li of this.list.children) li.classList.toggle('selected', li.dataset.id === id);
  }

  render() {
    const needle = this.search.value.trim().toLowerCase();
    this.list.replaceChildren();
    for (const item of this.items) {
      if (needle && !item.id.toLowerCase().includes(needle)) continue;
      const li = document.createElement('li');
      li.dataset.id = item.id;
      li.textContent = `${item.id}  ·  ${item.mesh}${item.visible ? '' : '  (hidden)'}`;
      li.classList.toggle('selected', item.id === this.selected);
      li.onclick = () => this.onSelect(item.id);
      this.list.append(li);
    }
    this.more.hidden = !this.cursor;
  }
}
