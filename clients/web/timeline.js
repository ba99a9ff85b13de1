// The time bar: the viewer's own scene time, scrubbed with the slider and played at real speed.
// Like the viewer's camera it travels in the stream's URL (time=, which leaves the scene alone),
// so playing costs one TLAS update of the animated instances per frame shown and writes no
// history; "Scene time" goes back to the scene's clock (set_time), and "Set scene time" makes
// the shown time the scene's for every client (one set_time edit, undoable).

/// Frames a second while playing: each reopens the stream at the next time.
const PLAY_FPS = 12;

export class TimeBar {
  /// `els`: {play, slider, label, length, scene, set}; `onChange(time | null)` when the shown
  /// time changes; `applyEdit(edits)` applies a batch.
  constructor(els, { onChange, applyEdit }) {
    this.els = els;
    this.onChange = onChange;
    this.applyEdit = applyEdit;
    this.time = null;     // the viewer's own time, or null: the scene's
    this.sceneTime = 0;   // the scene's clock, as GET /v1/scene last said
    this.timer = 0;
    els.slider.addEventListener('input', () => this.scrub(Number(els.slider.value)));
    els.length.addEventListener('change', () => this.setLength(Number(els.length.value)));
    els.play.addEventListener('click', () => (this.timer ? this.pause() : this.play()));
    els.scene.addEventListener('click', () => this.followScene());
    els.set.addEventListener('click', () => this.setSceneTime());
    this.show();
  }

  /// The scene's clock from a scene document (its `timeline`).
  sceneChanged(doc) {
    if (!doc.timeline) return;
    this.sceneTime = doc.timeline.time;
    if (this.time === null) this.show();
  }

  setLength(seconds) {
    if (!(seconds > 0)) return;
    this.els.slider.max = String(seconds);
  }

  scrub(time) {
    this.time = time;
    this.show();
    this.onChange(this.time);
  }

  play() {
    const start = performance.now();
    const from = this.time ?? this.sceneTime;
    this.els.play.classList.add('on');
    this.els.play.textContent = '❚❚';
    this.timer = setInterval(() => {
      const length = Number(this.els.slider.max);
      const t = from + (performance.now() - start) / 1000;
      this.scrub(length > 0 ? t % length : t);
    }, 1000 / PLAY_FPS);
  }

  pause() {
    clearInterval(this.timer);
    this.timer = 0;
    this.els.play.classList.remove('on');
    this.els.play.textContent = '▶';
  }

  followScene() {
    this.pause();
    this.time = null;
    this.show();
    this.onChange(null);
  }

  async setSceneTime() {
    if (this.time === null) return;
    const time = this.time;
    this.pause();
    if (await this.applyEdit([{ op: 'set_time', time }])) {
      this.sceneTime = time;
      this.followScene();
    }
  }

  show() {
    const t = this.time ?? this.sceneTime;
    this.els.slider.value = String(t);
    this.els.label.textContent = `${t.toFixed(2)} s` + (this.time === null ? ' (scene)' : '');
    this.els.scene.classList.toggle('on', this.time === null);
    this.els.set.disabled = this.time === null;
  }
}
