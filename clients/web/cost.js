// The cost panel: what each commit cost (ms, BLAS rebuilds and refits, TLAS action) as a live
// bar chart from GET /v1/events, and the last rebuild report in words.

const KEEP = 60;

export class CostPanel {
  constructor(canvas, text) {
    this.canvas = canvas;
    this.text = text;
    this.reports = [];
  }

  /// Adds a report (the same version twice counts once: the hello event and /v1/stats overlap).
  add(report) {
    if (this.reports.length && this.reports[this.reports.length - 1].version === report.version) return;
    this.reports.push(report);
    if (this.reports.length > KEEP) this.reports.shift();
    this.text.textContent = describe(report);
    this.text.classList.remove('muted');
    this.text.dataset.version = report.version;
    this.draw();
  }

  draw() {
    const c = this.canvas;
    const ctx = c.getContext('2d');
    const w = c.width, h = c.height;
    ctx.clearRect(0, 0, w, h);
    ctx.fillStyle = '#111316';
    ctx.fillRect(0, 0, w, h);
    if (!this.reports.length) return;
    const maxMs = Math.max(1, ...this.reports.map((r) => r.ms || 0));
    const maxCount = Math.max(1, ...this.reports.map((r) => (r.blas_rebuilds || 0) + (r.blas_refits || 0)));
    const bar = w / KEEP;
    this.reports.forEach((r, i) => {
      const x = i * bar;
      // Work: rebuilds (red) stacked under refits (amber), against the largest count shown.
      const rb = ((r.blas_rebuilds || 0) / maxCount) * (h - 14);
      const rf = ((r.blas_refits || 0) / maxCount) * (h - 14);
      ctx.fillStyle = '#e0645c';
      ctx.fillRect(x + 1, h - rb, bar - 2, rb);
      ctx.fillStyle = '#e6b450';
      ctx.fillRect(x + 1, h - rb - rf, bar - 2, rf);
      if (r.tlas && r.tlas.action === 'rebuild') {
        ctx.fillStyle = '#9b7fe6';
        ctx.fillRect(x + 1, 0, bar - 2, 4);
      }
    });
    // Milliseconds per commit as a line.
    ctx.strokeStyle = '#4fb3bf';
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    this.reports.forEach((r, i) => {
      const y = h - ((r.ms || 0) / maxMs) * (h - 14);
      const x = i * bar + bar / 2;
      if (i) ctx.lineTo(x, y); else ctx.moveTo(x, y);
    });
    ctx.stroke();
    ctx.fillStyle = '#8b929c';
    ctx.font = '10px system-ui';
    ctx.fillText(`max ${maxMs.toFixed(2)} ms · ${maxCount} BLAS ops`, 4, 11);
  }
}

/// A rebuild report (protocol/README "Rebuild reports") in words.
export function describe(r) {
  const mb = (b) => (b / 1048576).toFixed(2);
  const lines = [`version ${r.version}: ${r.ms !== undefined ? r.ms.toFixed(3) + ' ms' : 'planned'}`];
  const tlas = r.tlas || {};
  lines.push(`TLAS: ${tlas.action || '?'} over ${tlas.instances ?? '?'} instances (${tlas.strategy || '?'})`);
  lines.push(`BLAS: ${r.blas_rebuilds} rebuilt (${r.primitives_built} primitives), ${r.blas_refits} refit (${r.primitives_refit} primitives)`);
  for (const e of r.rebuilt || []) {
    const clusters = e.clusters ? ` as ${e.clusters} clusters` : '';
    // A mesh built with build.compact: its full-size first pass, then what it holds compacted.
    const compacted = e.uncompacted_bytes ? `, compacted ${mb(e.uncompacted_bytes)} → ${mb(e.bytes)} MiB` : '';
    lines.push(`  rebuilt ${e.mesh}: ${e.reason}, ${e.primitives} primitives${clusters}${compacted}`);
  }
  for (const e of r.refit || []) {
    // A clustered BLAS refits (and may rebuild) only the clusters the edit touched.
    const clusters = e.clusters
      ? ` in ${e.clusters_refit} of ${e.clusters} clusters` + (e.clusters_rebuilt ? `, ${e.clusters_rebuilt} rebuilt` : '')
      : '';
    lines.push(`  refit ${e.mesh}: ${e.primitives} primitives${clusters}`);
  }
  if (r.instances_changed) lines.push(`instances changed: ${r.instances_changed}`);
  if (r.world_transforms) lines.push(`world transforms recomputed: ${r.world_transforms}`);
  if (r.phases) {
    const p = r.phases;
    lines.push(`phases: plan ${p.plan_ms.toFixed(3)} · BLAS ${p.blas_ms.toFixed(3)} · TLAS ${p.tlas_ms.toFixed(3)} · sync ${p.sync_ms.toFixed(3)} ms`);
  }
  if (r.memory_bytes) {
    const c = r.memory_bytes.compaction;
    const saved = c && c.meshes ? ` · compaction saves ${mb(c.saved_bytes)} MiB over ${c.meshes} meshes` : '';
    lines.push(`memory: BLAS ${mb(r.memory_bytes.blas)} MiB · TLAS ${mb(r.memory_bytes.tlas)} MiB${saved}`);
  }
  return lines.join('\n');
}
