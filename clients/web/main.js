// The Strata viewer: the live frame stream (GET /v1/stream), a per-viewer camera and scene time
// (the time bar, timeline.js), picking and selection, edits through /v1/edits with If-Match,
// undo and redo (Ctrl+Z, Ctrl+Shift+Z or
// Ctrl+Y, and the history panel's buttons), the scene list, the history and the commit-cost
// panel fed by GET /v1/events. Plain ES modules, no build step; served by strata-server at GET /.

import { api, edit, enc, setToken, token, undo, withToken, ApiError, SCENE } from './api.js';
import { CameraControl } from './camera.js';
import { CostPanel } from './cost.js';
import { HistoryPanel } from './history.js';
import { Inspector } from './inspector.js';
import { ScenePanel } from './scene_panel.js';
import { TimeBar } from './timeline.js';

const $ = (id) => document.getElementById(id);

/// Page parameters: ?width=&height= fix the frame size (else it fits the window), and
/// ?fps=, ?quality=, ?max_samples= are passed to the stream (a slow link or a slow server).
/// ?still shows one rendered frame (?spp=, default 16) and opens nothing endless, so that a
/// headless browser's page load ends: screenshots and thumbnails. ?scene=NAME shows the named
/// scene NAME (api.js sends every request there).
const page = new URLSearchParams(location.search);
const pageNumber = (name, fallback) => {
  const v = Number(page.get(name));
  return page.has(name) && Number.isFinite(v) && v > 0 ? v : fallback;
};

/// Everything the panels share; exposed as window.strata for tests and the console.
const state = {
  version: null,        // newest scene version seen
  sceneCamera: null,    // the scene's camera (GET /v1/scene)
  size: [960, 540],
  selected: null,       // the selected instance's or group's document (kind: 'instance' | 'group')
  pastVersion: null,    // the version shown instead of the live stream (history's View), or null
  frameVersion: null,   // version of the newest frame shown
  streamUrl: '',
  listedVersion: null,  // the version the scene and history panels were last listed for
  listTimer: 0,
};
window.strata = state;

function message(text, kind = 'error') {
  const m = $('message');
  m.textContent = text;
  m.className = kind;
  m.hidden = !text;
}

function status(text) {
  $('status').textContent = SCENE ? `scene ${SCENE} · ${text}` : text;
}

// Step: the frame stream. The camera override travels in the URL; a new camera opens a new
// stream (the browser closes the old one, and the server stops rendering it).
let streamTimer = null;
let streamCount = 0;
const clientId = Math.random().toString(36).slice(2, 10);
/// The camera override as query parameters (none: the scene camera).
function cameraParams(camera) {
  if (!camera) return {};
  return {
    eye: camera.eye.map((v) => v.toFixed(4)).join(','),
    target: camera.target.map((v) => v.toFixed(4)).join(','),
    up: camera.up.map((v) => v.toFixed(4)).join(','),
    fov_y_deg: camera.fov_y_deg.toFixed(3),
  };
}

/// The viewer's own scene time as a query parameter (none: the scene's time).
function timeParams() {
  return timeBar.time === null ? {} : { time: timeBar.time.toFixed(3) };
}

/// Shows `url` in the frame at the frame size.
function showFrame(url) {
  const [w, h] = state.size;
  const img = $('frame');
  img.width = w;
  img.height = h;
  img.src = url;
}

function openStream(camera) {
  const [w, h] = state.size;
  const params = {
    width: w, height: h, quality: pageNumber('quality', 80), fps: pageNumber('fps', 20),
    max_samples: pageNumber('max_samples', 32), ...cameraParams(camera), ...timeParams(),
  };
  const past = state.pastVersion;
  if (past !== null) {
    // The history's View: the scene as version N left it, from the server's data directory.
    params.at_version = past;
  } else if (state.selected && state.selected.kind === 'instance') {
    // The selected instance is tinted by the server, pixel by pixel, from the frame's ids.
    params.highlight = state.selected.id;
  }
  const key = JSON.stringify(params);
  if (key === state.streamKey) return;
  state.streamKey = key;
  // Unique per stream: the browser would share an in-flight image between equal URLs.
  params.client = `${clientId}-${++streamCount}`;
  const url = withToken('/v1/stream', params);
  state.streamUrl = url;
  if (past !== null) watchPast(past, url);
  showFrame(url);
}

// Step: a past version. The history's View shows the scene as version N left it: the frame
// stream at that version (GET /v1/stream?at_version=N, which accumulates and then stays), until
// Back to live. <body data-past="N"> says which version is shown once its first frame is in
// ("failed" when the server could not show it, with its reason).
function watchPast(version, url) {
  const img = $('frame');
  const shown = () => {
    img.removeEventListener('error', failed);
    if (state.pastVersion === version && state.streamUrl === url) {
      document.body.dataset.past = String(version);
    }
  };
  const failed = async () => {
    img.removeEventListener('load', shown);
    if (state.pastVersion !== version || state.streamUrl !== url) return;
    document.body.dataset.past = 'failed';
    // An <img> hears no reason: a one-pixel render of that version says why.
    const probe = withToken('/v1/render', { width: 1, height: 1, at_version: version });
    const answer = await fetch(probe);
    const problem = answer.ok ? {} : await answer.json().catch(() => ({}));
    message(`Cannot show version ${version}: ${problem.detail || 'the stream failed'}`);
  };
  img.addEventListener('load', shown, { once: true });
  img.addEventListener('error', failed, { once: true });
}

function viewPast(version) {
  state.pastVersion = version;
  $('past-version').textContent = String(version);
  $('past').hidden = false;
  delete document.body.dataset.past;
  state.selected = null;  // picks and edits act on the live scene
  inspector.show(null);
  scenePanel.mark(null, null);
  drawSelection();
  openStream(controls.camera);
}

function backToLive() {
  state.pastVersion = null;
  $('past').hidden = true;
  delete document.body.dataset.past;
  message('');
  openStream(controls.camera);
}

/// ?still: one frame from GET /v1/render. Once it is shown, the title names its version and
/// <body data-still="ready"> (or "failed") tells a script the page is done.
function renderStill(camera) {
  const [w, h] = state.size;
  const img = $('frame');
  img.addEventListener('load', () => {
    document.title = `Strata · ${SCENE ? SCENE + ' · ' : ''}version ${state.version} (still)`;
    document.body.dataset.still = 'ready';
  }, { once: true });
  img.addEventListener('error', () => {
    document.body.dataset.still = 'failed';
    message('The frame could not be rendered.');
  }, { once: true });
  showFrame(withToken('/v1/render', {
    width: w, height: h, spp: pageNumber('spp', 16), ...cameraParams(camera), ...timeParams(),
  }));
}

/// Throttles stream reopening while the camera is being dragged.
function cameraChanged(camera) {
  $('follow').classList.toggle('on', camera === null);
  clearTimeout(streamTimer);
  streamTimer = setTimeout(() => {
    if (page.has('still')) renderStill(camera);
    else openStream(camera);
    drawSelection();
  }, camera ? 60 : 0);
  drawSelection();
}

/// The camera the frame shows: the override or the scene camera.
function viewCamera() {
  return controls.camera || state.sceneCamera;
}

// Step: the selection highlight. The server tints the selected instance's pixels in the stream
// (highlight=<id>), so the overlay only needs clearing; a selection change reopens the stream.
function drawSelection() {
  const canvas = $('overlay');
  const [w, h] = state.size;
  canvas.width = w;
  canvas.height = h;
  canvas.getContext('2d').clearRect(0, 0, w, h);
}

async function refreshScene() {
  const { doc } = await api('/v1/scene');
  state.sceneCamera = doc.camera;
  timeBar.sceneChanged(doc);
  // Never back: an answer overtaken by the viewer's own newer edit or undo must not make the
  // next undo's If-Match name the older version.
  state.version = Math.max(doc.version, state.version ?? 0);
  status(`version ${doc.version} · ${doc.counts.instances} instances · ${doc.counts.triangles} triangles`);
  return doc;
}

// Step: picking. The pick asks with the frame's own size and camera, so it names what the frame
// shows under the click.
async function pickAt(x, y) {
  if (state.pastVersion !== null) {
    message('Picking and editing act on the live scene: go back to live first.', 'info');
    return;
  }
  const [w, h] = state.size;
  const params = { x: Math.floor(x), y: Math.floor(y), width: w, height: h, ...timeParams() };
  const cam = controls.camera;
  if (cam) {
    params.eye = cam.eye.join(',');
    params.target = cam.target.join(',');
    params.up = cam.up.join(',');
    params.fov_y_deg = cam.fov_y_deg;
  }
  try {
    const { doc } = await api('/v1/pick?' + new URLSearchParams(params));
    if (!doc.hit) {
      select(null);
      return;
    }
    await select(doc.hit.instance, doc.hit);
  } catch (e) {
    message('Pick failed: ' + e.message);
  }
}

/// The groups from the root down to `parent` (walking GET /v1/scene/groups/{id}).
async function groupPath(parent) {
  const path = [];
  for (let id = parent; id && path.length < 64; ) {
    path.unshift(id);
    const { doc } = await api('/v1/scene/groups/' + enc(id));
    id = doc.parent;
  }
  return path;
}

async function readSelected(kind, id) {
  const { doc } = await api(`/v1/scene/${kind === 'group' ? 'groups' : 'instances'}/` + enc(id));
  doc.kind = kind;
  doc.path = await groupPath(doc.parent);
  // An instance's mesh: its kind, primitives and build options (compaction among them) are
  // shown with it.
  if (kind === 'instance') {
    doc.mesh_doc = (await api('/v1/scene/meshes/' + enc(doc.mesh))).doc;
    doc.mesh_build = doc.mesh_doc.build;
  }
  return doc;
}

function selectionChanged() {
  const s = state.selected;
  scenePanel.mark(s ? s.id : null, s ? s.kind : null);
  drawSelection();
  openStream(controls.camera);
}

async function select(id, hit, kind = 'instance') {
  if (!id) {
    state.selected = null;
    inspector.show(null);
    selectionChanged();
    return;
  }
  try {
    const doc = await readSelected(kind, id);
    if (hit && hit.group_path) doc.path = hit.group_path;
    state.selected = doc;
    inspector.show(doc);
    selectionChanged();
  } catch (e) {
    message(`Cannot read ${kind} ${id}: ${e.message}`);
  }
}

/// Reloads the selection (after a commit: another client may have changed it). While the user
/// is typing into the inspector (`force` unset), the fields keep their values: the apply that
/// follows is checked against the version they were read at. `removedBy` says who removed it
/// when it is gone.
async function reloadSelection(force = false, removedBy = 'another client') {
  if (!state.selected) return;
  const { id, kind } = state.selected;
  try {
    const doc = await readSelected(kind, id);
    if (!force && inspector.dirty) {
      inspector.outdated(doc.version);
      return;
    }
    state.selected = doc;
    inspector.show(doc);
  } catch (e) {
    if (e instanceof ApiError && e.status === 404) {
      message(`The selected ${kind} '${id}' was removed by ${removedBy}.`, 'info');
      select(null);
    }
  }
  drawSelection();
}

// Step: edits from the inspector, each one batch with If-Match on the version the panel shows.
async function applyEdit(edits, basedOn) {
  try {
    const { doc } = await edit(edits, basedOn);
    message(`Applied (version ${doc.version}).`, 'info');
    state.version = doc.version;
    sceneMoved(doc.version);
    await reloadSelection(true);
    return true;
  } catch (e) {
    if (e instanceof ApiError && e.status === 412) {
      const now = e.etag !== null ? ` (now version ${e.etag})` : '';
      message(`Conflict: the scene changed since version ${basedOn}${now}: another client edited it. ` +
              'Nothing was applied; the panel now shows the current values, check them and apply again.',
              'conflict');
      await reloadSelection(true);
    } else {
      message('Edit refused: ' + e.message);
    }
    return false;
  }
}

// Step: undo and redo, of the whole scene's newest batch (anyone's), with If-Match on the version
// the viewer shows: what is taken back is what the user sees, or nothing (a 412 says so, and the
// next press acts on the version it names). Presses queue: each is sent once the one before has
// answered, at the version that one made (a held key undoes step by step).
let undoQueue = Promise.resolve();
function undoRedo(redo) {
  undoQueue = undoQueue.then(() => undoRedoNow(redo));
  return undoQueue;
}

async function undoRedoNow(redo) {
  const word = redo ? 'Redo' : 'Undo';
  const basedOn = state.version;
  try {
    const { doc } = await undo(redo, basedOn);
    const target = redo ? doc.redone : doc.undone;
    message(`${redo ? 'Redone' : 'Undone'}: version ${target}'s batch (now version ${doc.version}).`, 'info');
    state.version = doc.version;
    sceneMoved(doc.version);
    if (page.has('still')) renderStill(controls.camera);
    refreshScene().catch(() => {});
    reloadSelection(true, `the ${word.toLowerCase()} of version ${target}`);
  } catch (e) {
    if (e instanceof ApiError && e.status === 409) {
      message(redo ? 'Nothing to redo.' : 'Nothing to undo.', 'info');
    } else if (e instanceof ApiError && e.status === 412) {
      message(`${word} not applied: the scene changed since version ${basedOn} (now version ${e.etag}): ` +
              `another client edited it. Press again to ${word.toLowerCase()} the newest batch.`, 'conflict');
      if (e.etag !== null) state.version = e.etag;
      historyPanel.refresh();
    } else {
      message(`${word} refused: ` + e.message);
    }
  }
}

/// Whether a key goes to a field the user types into (its own Ctrl+Z undoes the typing).
function typing(target) {
  if (!target || !target.tagName) return false;
  if (target.isContentEditable || target.tagName === 'TEXTAREA' || target.tagName === 'SELECT') return true;
  return target.tagName === 'INPUT' &&
    !['checkbox', 'radio', 'color', 'range', 'button', 'submit', 'reset'].includes(target.type);
}

document.addEventListener('keydown', (e) => {
  if (!(e.ctrlKey || e.metaKey) || e.altKey || typing(e.target)) return;
  const k = e.key.toLowerCase();
  if (k === 'z') undoRedo(e.shiftKey);
  else if (k === 'y' && !e.shiftKey) undoRedo(true);
  else return;
  e.preventDefault();
});

/// The scene is at `version` now: list the scene and the history again (at most every 300 ms)
/// when it is new to them (a no-work commit keeps its version).
function sceneMoved(version) {
  if (version === state.listedVersion) return;
  state.listedVersion = version;
  clearTimeout(state.listTimer);
  state.listTimer = setTimeout(() => {
    scenePanel.refresh();
    historyPanel.refresh();
  }, 300);
}

// Step: commit events, for the cost panel and to notice other clients' edits.
let events = null;
function openEvents() {
  if (events) events.close();
  events = new EventSource(withToken('/v1/events'));
  events.addEventListener('hello', (e) => {
    const d = JSON.parse(e.data);
    if (d.report) costPanel.add(d.report);
  });
  events.addEventListener('commit', async (e) => {
    const d = JSON.parse(e.data);
    costPanel.add(d.report);
    sceneMoved(d.version);
    await refreshScene().catch(() => {});
    if (!controls.camera) drawSelection();
    if (state.selected) reloadSelection();
  });
  events.onerror = () => status('event stream interrupted; retrying…');
}

function fitSize() {
  if (page.has('width') && page.has('height')) {
    state.size = [Math.round(pageNumber('width', 640)), Math.round(pageNumber('height', 360))];
    return;
  }
  const pane = $('view-pane');
  const w = Math.max(320, Math.min(1280, Math.floor((pane.clientWidth - 16) / 16) * 16));
  state.size = [w, Math.round((w * 9) / 16)];
}

// Step: token. With a server that needs one, the first request answers 401: ask once, keep it
// in sessionStorage for this tab.
function askToken(reason) {
  $('token-input').value = token();
  $('token-dialog').querySelector('p').textContent = reason ||
    'This server needs a token. It stays in this tab only (sessionStorage).';
  if (!$('token-dialog').open) $('token-dialog').showModal();
}

async function start() {
  message('');
  try {
    await refreshScene();
  } catch (e) {
    if (e instanceof ApiError && e.status === 401) {
      status('token needed');
      askToken(token() ? 'The token was refused; enter the right one.' : undefined);
      return;
    }
    message('Cannot reach the server: ' + e.message, 'unreachable');
    return;
  }
  fitSize();
  if (page.has('still')) {
    renderStill(controls.camera);
  } else {
    openStream(controls.camera);
    openEvents();
  }
  scenePanel.load();
  historyPanel.refresh();
}

const controls = new CameraControl($('view'), {
  onChange: cameraChanged,
  onClick: pickAt,
  getSceneCamera: () => state.sceneCamera,
});
const inspector = new Inspector($('inspector'), {
  applyEdit, onSelectGroup: (id) => select(id, null, 'group'),
  onFrame: (bounds) => controls.frame(bounds, state.size[0] / state.size[1]),
});
const scenePanel = new ScenePanel($('scene-list'), $('scene-search'), $('scene-more'), {
  onSelect: (id, kind) => select(id, null, kind),
});
const timeBar = new TimeBar({
  play: $('time-play'), slider: $('time-slider'), label: $('time-label'),
  length: $('time-length'), scene: $('time-scene'), set: $('time-set'),
}, { onChange: () => cameraChanged(controls.camera), applyEdit: (edits) => applyEdit(edits) });
const costPanel = new CostPanel($('cost-chart'), $('last-report'));
const historyPanel = new HistoryPanel($('history-list'), $('history-stacks'), $('history-undo'),
                                      $('history-redo'), {
  onUndo: () => undoRedo(false), onRedo: () => undoRedo(true), onView: viewPast,
});
$('past-live').addEventListener('click', backToLive);

$('follow').addEventListener('click', () => controls.follow());
$('follow').classList.add('on');
$('token-open').addEventListener('click', () => askToken());
$('token-form').addEventListener('submit', () => {
  setToken($('token-input').value.trim());
  state.streamKey = '';
  start();
});
$('token-clear').addEventListener('click', () => {
  setToken('');
  $('token-dialog').close();
});
// A frame arriving answers "cannot reach the server", and only that: a conflict or a refused edit
// stays until the user's next action.
$('frame').addEventListener('load', () => {
  if ($('message').className === 'unreachable') message('');
});
$('frame').addEventListener('error', () => {
  if (state.streamUrl) status('frame stream interrupted');
});

state.select = select;
state.timeBar = timeBar;
state.pickAt = pickAt;
state.controls = controls;
state.undoRedo = undoRedo;
start();
