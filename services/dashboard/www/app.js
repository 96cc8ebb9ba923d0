// The shop-floor page: renders the state embedded in the page, then applies the server's events
// (/api/events, server-sent events) without reloading. Every text goes through textContent.
(function () {
  'use strict';
  const S = JSON.parse(document.getElementById('state').textContent);
  const byId = (id) => document.getElementById(id);
  const HAS_CHART = typeof window.Chart === 'function';
  const AXIS_COLOURS = ['#4fa3ff', '#ffb84d', '#6fdc8c', '#ff6f91', '#c792ea', '#7fdbff'];
  const stations = new Map();  // id -> {data, el: {...}, chart}
  let openJob = null;

  function el(tag, cls, text) {
    const e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined && text !== null) e.textContent = String(text);
    return e;
  }
  function dur(s) {
    if (s === null || s === undefined) return '—';
    s = Math.round(s);
    if (s < 60) return s + ' s';
    if (s < 3600) return Math.floor(s / 60) + ' min ' + String(s % 60).padStart(2, '0') + ' s';
    return Math.floor(s / 3600) + ' h ' + String(Math.floor((s % 3600) / 60)).padStart(2, '0') + ' min';
  }
  function time(iso) {
    if (!iso) return '—';
    const d = new Date(iso);
    return d.toLocaleTimeString([], { hour12: false });
  }
  function val(v) { return v === null || v === undefined || v === '' ? '—' : v; }

  // One sentence a supervisor reads first: what the station is doing, or why it is not.
  function doing(st) {
    if (!st.online) return 'Offline: its CNC is not announced on the bus';
    const prog = st.program ? st.program : 'a program';
    const on = st.pallet ? ' on pallet ' + st.pallet : '';
    const fault = st.condition === 'FAULT' ? 'FAULT: ' : '';
    switch (st.execution) {
      case 'ACTIVE': return fault + 'Running ' + prog + on + (st.status_text ? ' · ' + st.status_text : '');
      case 'FEED_HOLD': return fault + 'Feed hold: ' + prog + on + ' stopped on its path';
      case 'INTERRUPTED': return fault + 'Interrupted: ' + prog + on;
      case 'WAIT': return fault + (st.status_text ? st.status_text[0].toUpperCase() + st.status_text.slice(1) + ': ' : 'Waiting for an input: ') + prog + on;
      case 'PROGRAM_STOPPED':
      case 'OPTIONAL_STOP': return fault + (st.status_text || (st.execution === 'OPTIONAL_STOP' ? 'Optional stop (M01)' : 'Program stop (M00)') + on + ': press cycle start');
      case 'STOPPED': return fault + 'Stopped' + on;
      case 'PROGRAM_COMPLETED': return fault + 'Program completed' + on;
      case 'READY': {
        const next = st.queue.find((q) => q.state === 'DISPATCHED');
        if (fault) return fault + 'idle, needs an operator';
        return next ? 'Ready: pallet ' + next.pallet + ' is on its way' : 'Idle, ready for work';
      }
      default: return fault + 'No status yet';
    }
  }

  function makeCard(st) {
    const c = el('div', 'card');
    c.id = 'station-' + st.id;
    const top = el('div', 'top');
    const e = {
      id: el('span', 'id', st.id),
      kind: el('span', 'kind'),
      badge: el('span', 'badge'),
      cond: el('span', 'cond'),
      doing: el('div', 'doing'),
      facts: el('div', 'facts'),
      alarm: el('div', 'alarm'),
      wait: el('div', 'wait'),
      queue: el('div', 'queue'),
      backlog: el('div', 'backlog'),
      plot: el('div', 'plot'),
      motion: el('div', 'motion'),
    };
    const gap = el('span', 'gap');
    top.append(e.id, gap, e.cond, e.badge);
    const body = el('div', 'body');
    // The program's toolpath, live (toolpath section below): opens over the page.
    e.pathBtn = el('button', 'pathbtn', 'Toolpath');
    e.pathBtn.type = 'button';
    e.pathBtn.addEventListener('click', () => openPath(st.id));
    e.kindRow = el('div', 'kindrow');
    e.kindRow.append(e.kind, e.pathBtn);
    body.append(e.kindRow, e.doing, e.facts, e.alarm, e.wait, e.queue, e.backlog, e.plot, e.motion);
    c.append(top, body);
    e.fact = {};
    for (const [k, label] of [['program', 'program'], ['line', 'line'], ['pallet', 'pallet'], ['tool', 'tool'],
                              ['part_count', 'parts'], ['queued', 'queued'], ['tools', 'tool table'], ['alarm_code', 'alarm']]) {
      const d = el('div');
      d.append(el('span', null, label));
      const b = el('b', 'f-' + k);
      d.append(b);
      e.facts.append(d);
      e.fact[k] = b;
    }
    e.backlog.append(el('span', null, 'backlog'));
    e.bar = el('div', 'bar');
    e.barFill = el('i');
    e.bar.append(e.barFill);
    e.backlogText = el('b', 'backlog-s');
    e.backlog.append(e.bar, e.backlogText);
    const canvas = el('canvas');
    e.plot.append(canvas);
    const rec = { data: st, el: e, card: c, chart: null, trail: [] };
    if (HAS_CHART) rec.chart = makeAxisChart(canvas, st.axis_defs);
    return rec;
  }

  // The station's axes as the server describes them (label, rotary): degrees on the right-hand scale.
  function makeAxisChart(canvas, axes) {
    return new Chart(canvas, {
      type: 'line',
      data: {
        datasets: axes.map((a, i) => ({
          label: a.label, data: [], borderColor: AXIS_COLOURS[i % AXIS_COLOURS.length], borderWidth: 1.5,
          pointRadius: 0, yAxisID: a.rotary ? 'deg' : 'mm',
        })),
      },
      options: {
        animation: false, responsive: true, maintainAspectRatio: false, parsing: false, normalized: true,
        plugins: { legend: { labels: { color: '#aab3bf', boxWidth: 10, font: { size: 10 } } }, tooltip: { enabled: false } },
        scales: {
          x: { type: 'linear', ticks: { color: '#7d8794', font: { size: 10 }, callback: (v) => (v === 0 ? 'now' : v + ' s') },
               grid: { color: '#262c34' } },
          mm: { position: 'left', ticks: { color: '#7d8794', font: { size: 10 } }, grid: { color: '#262c34' },
                title: { display: true, text: 'mm', color: '#7d8794', font: { size: 10 } } },
          deg: { position: 'right', display: axes.some((a) => a.rotary), ticks: { color: '#7d8794', font: { size: 10 } },
                 grid: { display: false }, title: { display: true, text: 'deg', color: '#7d8794', font: { size: 10 } } },
        },
      },
    });
  }

  function maxBacklog() {
    let m = 60;
    for (const s of stations.values()) m = Math.max(m, s.data.backlog_s || 0);
    return m;
  }

  function renderStation(st) {
    let rec = stations.get(st.id);
    if (!rec) {
      rec = makeCard(st);
      stations.set(st.id, rec);
      byId('stations').append(rec.card);
    }
    rec.data = st;
    const e = rec.el, c = rec.card;
    c.className = 'card x-' + st.execution + ' c-' + st.condition;
    c.dataset.execution = st.execution;
    c.dataset.condition = st.condition;
    c.dataset.online = st.online;
    // The words for dialect and machine kind come from the server (the registry, the machine tables).
    const words = S.vocabulary || {};
    const dialect = (words.dialects || {})[st.dialect] || st.dialect;
    const kind = (words.kinds || {})[st.kind] || st.kind;
    e.kind.textContent = dialect + ' ' + kind + ' · ' + st.axes.join(' ');
    c.title = st.description || '';
    e.badge.textContent = st.execution.replace(/_/g, ' ');
    e.badge.className = 'badge execution';
    e.cond.textContent = st.condition;
    e.cond.className = 'cond condition ' + st.condition;
    e.cond.style.display = st.condition === 'UNAVAILABLE' ? 'none' : '';
    e.doing.textContent = doing(st);
    e.fact.program.textContent = val(st.program);
    e.fact.line.textContent = val(st.line);
    e.fact.pallet.textContent = val(st.pallet);
    e.fact.tool.textContent = val(st.tool);
    e.fact.part_count.textContent = val(st.part_count);
    e.fact.queued.textContent = st.queued;
    const t = st.tools || { count: 0, worn: 0, broken: 0 };
    e.fact.tools.textContent = t.count + ' tools' + (t.worn ? ', ' + t.worn + ' worn' : '') + (t.broken ? ', ' + t.broken + ' broken' : '');
    e.fact.alarm_code.textContent = val(st.alarm_code);
    // Alarm and message
    e.alarm.replaceChildren();
    e.alarm.style.display = st.alarm_text || st.alarm_code ? '' : 'none';
    e.alarm.className = 'alarm ' + st.condition;
    if (st.alarm_code) e.alarm.append(el('b', null, st.alarm_code));
    if (st.alarm_text) e.alarm.append(document.createTextNode(st.alarm_text));
    // Pallets that wait and why they cannot come here
    e.wait.replaceChildren();
    e.wait.style.display = st.waiting.length ? '' : 'none';
    for (const w of st.waiting) {
      const d = el('div', 'waiting');
      d.dataset.job = w.job;
      d.dataset.pallet = w.pallet;
      d.append(el('b', null, 'Pallet ' + w.pallet + ' waits: '), document.createTextNode(w.why + ' '),
               el('span', 'job', '(job ' + w.job + (w.route ? ', route ' + w.route : '') + ')'));
      e.wait.append(d);
    }
    const queued = st.queue.filter((q) => q.state !== 'RUNNING');
    e.queue.textContent = queued.length ? 'Queued here: ' + queued.map((q) => 'pallet ' + q.pallet + ' (job ' + q.job + ')').join(', ') : '';
    e.backlogText.textContent = dur(st.backlog_s);
    for (const r of stations.values()) r.el.barFill.style.width = Math.min(100, (100 * (r.data.backlog_s || 0)) / maxBacklog()) + '%';
    e.pathBtn.disabled = !st.program;
    e.pathBtn.title = st.program ? 'the toolpath of ' + st.program + ', live' : 'no program run yet';
    pathStation(st);
  }

  function pushAxes(id, t, pos, feed, rpm, liveRpm) {
    const rec = stations.get(id);
    if (!rec) return;
    rec.trail.push([t, pos]);
    while (rec.trail.length && rec.trail[0][0] < t - 60) rec.trail.shift();
    pathAxes(rec, pos);
    rec.el.motion.textContent = 'feed ' + Math.round(feed) + ' mm/min · spindle ' + Math.round(Math.abs(rpm)) + ' rpm' +
      (rec.data.live_tool ? ' · live tool ' + Math.round(Math.abs(liveRpm || 0)) + ' rpm' : '') +
      (pos.length ? ' · ' + rec.data.axes.map((n, i) => n.split(' ')[0] + ' ' + pos[i].toFixed(3)).join('  ') : '');
  }

  function drawAxes() {
    const now = Date.now() / 1000 - skew;
    for (const rec of stations.values()) {
      if (!rec.chart) continue;
      rec.chart.data.datasets.forEach((ds, i) => {
        ds.data = rec.trail.map(([t, p]) => ({ x: Math.round((t - now) * 10) / 10, y: p[i] }));
      });
      rec.chart.options.scales.x.min = -60;
      rec.chart.options.scales.x.max = 0;
      rec.chart.update('none');
    }
  }

  // ---- toolpath (docs/dashboard.md "Toolpath") ----
  // The server draws the program the station runs (/api/station/<ID>/path: the plot's SVG and its moves in
  // order); the page marks the moves the machine has done and moves a tool marker with the axis positions it
  // already receives. The moves done are found by position: from the last one done, the first move whose
  // path passes within a tolerance of where the tool is (monotone: a run's moves happen in order).
  let pv = null;  // {station, program, moves, paths: [[elements of seq i]], views, done, tol, idle}
  const SVGNS = 'http://www.w3.org/2000/svg';

  function pathBox() {
    let box = byId('pathview');
    if (box) return box;
    box = el('div', 'pathview');
    box.id = 'pathview';
    const head = el('div', 'pathhead');
    const title = el('b', 'pathtitle');
    const info = el('span', 'pathinfo');
    const key = el('span', 'pathkey', 'bold: done · faded: to come · red ring: the tool');
    const link = el('a', 'pathsvg', 'SVG');
    link.target = '_blank';
    const close = el('button', 'pathclose', 'Close');
    close.type = 'button';
    close.addEventListener('click', closePath);
    head.append(title, info, el('span', 'gap'), key, link, close);
    box.append(head, el('div', 'pathbody'));
    document.body.append(box);
    document.addEventListener('keydown', (k) => { if (k.key === 'Escape') closePath(); });
    return box;
  }

  function closePath() {
    const box = byId('pathview');
    if (box) box.style.display = 'none';
    pv = null;
  }

  function openPath(id) {
    const rec = stations.get(id);
    if (!rec || !rec.data.program) return;
    const box = pathBox();
    box.style.display = '';
    box.dataset.station = id;
    pv = { station: id, program: rec.data.program, moves: [], paths: [], views: [], done: 0, tol: 1, idle: IDLE.has(rec.data.execution) };
    loadPath();
  }

  function loadPath() {
    const want = pv;
    const box = byId('pathview');
    const q = '?program=' + encodeURIComponent(want.program);
    box.querySelector('.pathtitle').textContent = want.station + ' · ' + want.program;
    box.querySelector('.pathinfo').textContent = 'drawing…';
    box.querySelector('.pathsvg').href = '/station/' + want.station + '/path.svg' + q;
    box.dataset.state = 'loading';
    fetch('/api/station/' + want.station + '/path' + q).then((r) => r.json()).then((j) => {
      if (pv !== want) return;
      const body = box.querySelector('.pathbody');
      if (j.error) {
        box.dataset.state = 'error';
        box.querySelector('.pathinfo').textContent = j.error;
        body.replaceChildren();
        return;
      }
      const doc = new DOMParser().parseFromString(j.svg, 'image/svg+xml');
      const svg = document.importNode(doc.documentElement, true);
      svg.removeAttribute('width');
      svg.removeAttribute('height');
      body.replaceChildren(svg);
      want.moves = j.moves;
      want.paths = j.moves.map(() => []);
      for (const p of svg.querySelectorAll('path[data-seq]')) want.paths[Number(p.dataset.seq)].push(p);
      want.views = [...svg.querySelectorAll('g.view')].map(viewOf);
      want.tol = tolerance(j);
      box.querySelector('.pathinfo').textContent = j.dialect + ' · ' + j.machine + ' · from ' + j.source + ' · ' + j.motion_ops + ' motion ops' + (j.note ? ' · ' + j.note : '');
      box.dataset.moves = j.moves.length;
      box.dataset.state = 'drawn';
      setDone(0);
      const last = stations.get(want.station).trail.slice(-1)[0];
      if (last) pathAxes(stations.get(want.station), last[1]);
    }).catch((err) => {
      if (pv !== want) return;
      box.dataset.state = 'error';
      box.querySelector('.pathinfo').textContent = 'no toolpath: ' + err;
    });
  }

  // A view's mapping from millimetres to the SVG page (interp/plot writes it on each g.view) and its marker.
  function viewOf(g) {
    const v = {};
    for (const k of ['h', 'v', 'left', 'top', 'h0', 'v0', 'scale']) v[k] = Number(g.dataset[k]);
    const clip = g.querySelector('g[clip-path]') || g;
    v.tool = document.createElementNS(SVGNS, 'g');
    v.tool.setAttribute('class', 'tool');
    const ring = document.createElementNS(SVGNS, 'circle');
    ring.setAttribute('r', '7');
    const cross = document.createElementNS(SVGNS, 'path');
    cross.setAttribute('d', 'M -12 0 H 12 M 0 -12 V 12');
    v.tool.append(ring, cross);
    clip.append(v.tool);
    return v;
  }

  // Within 1 % of the path's size, at least 1 mm: the servo's following error and the 5 Hz samples.
  function tolerance(j) {
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (const m of j.moves) for (const p of [m.from, m.to]) p.forEach((x, i) => { lo[i] = Math.min(lo[i], x); hi[i] = Math.max(hi[i], x); });
    const d = j.moves.length ? Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) : 0;
    return Math.max(1, d / 100);
  }

  // How far the tool at p is from a move's path, and the move's direction there (an arc's tangent).
  function nearMove(p, m) {
    if (m.center) {
      const [f, s] = m.plane, n = 3 - f - s;
      const r = Math.hypot(m.from[f] - m.center[f], m.from[s] - m.center[s]);
      const rf = p[f] - m.center[f], rs = p[s] - m.center[s];
      const radial = Math.abs(Math.hypot(rf, rs) - r);
      const along = Math.max(0, Math.min(m.from[n], m.to[n]) - p[n], p[n] - Math.max(m.from[n], m.to[n]));
      const dir = [0, 0, 0];
      dir[f] = m.cw ? rs : -rs;
      dir[s] = m.cw ? -rf : rf;
      dir[n] = m.to[n] - m.from[n];
      return { dist: Math.hypot(radial, along), dir };
    }
    const d = m.to.map((x, i) => x - m.from[i]);
    const len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const t = len2 ? Math.max(0, Math.min(1, ((p[0] - m.from[0]) * d[0] + (p[1] - m.from[1]) * d[1] + (p[2] - m.from[2]) * d[2]) / len2)) : 0;
    return { dist: Math.hypot(...p.map((x, i) => x - (m.from[i] + t * d[i]))), dir: d };
  }

  // The move under way: from the current one, the first the tool is on and, when it moved since the last
  // sample, moving along (a path that comes back over itself: the way back is the later move).
  function moveUnderWay(p, step) {
    const moving = Math.hypot(...step) > pv.tol / 4;
    for (let i = pv.done; i < pv.moves.length; i++) {
      const n = nearMove(p, pv.moves[i]);
      if (n.dist > pv.tol) continue;
      if (!moving || step[0] * n.dir[0] + step[1] * n.dir[1] + step[2] * n.dir[2] > 0) return i;
    }
    return pv.done;
  }

  function setDone(n) {
    for (let i = pv.done; i < n; i++) for (const p of pv.paths[i]) p.classList.add('done');
    for (let i = n; i < pv.done; i++) for (const p of pv.paths[i]) p.classList.remove('done');
    pv.done = n;
    byId('pathview').dataset.done = n;
    liveLook();
  }

  // Once a run is followed (or has been), the moves to come fade and the moves done stand out.
  function liveLook() {
    const svg = byId('pathview').querySelector('svg');
    if (svg) svg.classList.toggle('live', pv.done > 0 || !pv.idle);
  }

  // The station's axis positions (its axis_defs order) as the plot's X Y Z, X as a radius.
  function pathAxes(rec, pos) {
    if (!pv || pv.station !== rec.data.id || !pv.views.length) return;
    const p = [0, 0, 0];
    (rec.data.axis_defs || []).forEach((a, i) => {
      const k = 'XYZ'.indexOf(a.name);
      if (k >= 0 && pos[i] !== undefined && pos[i] !== null) p[k] = a.diameter ? pos[i] / 2 : pos[i];
    });
    for (const v of pv.views)
      v.tool.setAttribute('transform', 'translate(' + (v.left + (p[v.h] - v.h0) * v.scale).toFixed(1) + ' ' + (v.top + (v.v0 - p[v.v]) * v.scale).toFixed(1) + ')');
    const step = pv.at ? p.map((x, i) => x - pv.at[i]) : [0, 0, 0];
    pv.at = p;
    if (pv.idle) return;
    const i = moveUnderWay(p, step);
    if (i > pv.done) setDone(i);
  }

  // A new program on the station draws its path; a run that starts starts it over; one that ends without a
  // fault is done. Between runs (READY, PROGRAM_COMPLETED) the marker moves and the moves done stay.
  const IDLE = new Set(['READY', 'PROGRAM_COMPLETED', 'UNAVAILABLE']);
  function pathStation(st) {
    if (!pv || pv.station !== st.id) return;
    const idle = IDLE.has(st.execution);
    if (st.program && st.program !== pv.program) {
      pv.program = st.program;
      pv.idle = idle;
      loadPath();
      return;
    }
    if (!idle && pv.idle && pv.moves.length) setDone(0);
    if (idle && !pv.idle && pv.moves.length && st.condition !== 'FAULT') setDone(pv.moves.length);
    pv.idle = idle;
    if (pv.moves.length) liveLook();
  }

  // ---- jobs ----
  const jobs = new Map();
  function jobRow(j) {
    let tr = byId('job-' + j.id);
    if (!tr) {
      tr = el('tr', 'job');
      tr.id = 'job-' + j.id;
      tr.addEventListener('click', () => toggleLog(j.id));
      const body = document.querySelector('#jobs tbody');
      // Newest first.
      let before = null;
      for (const r of body.querySelectorAll('tr.job')) if (Number(r.id.slice(4)) < j.id) { before = r; break; }
      body.insertBefore(tr, before);
    }
    tr.dataset.state = j.state;
    tr.replaceChildren(
      el('td', null, j.id),
      (() => { const td = el('td'); td.append(el('span', 'st st-' + j.state, j.state)); return td; })(),
      el('td', null, j.route || j.schedule || j.kind),
      el('td', null, j.pallet || '—'),
      el('td', null, val(j.station)),
      el('td', null, j.op_index + '/' + j.op_count),
      el('td', 'reason', j.reason || ''),
      el('td', null, time(j.started)),
      el('td', null, j.cycle_s === null ? '—' : j.cycle_s.toFixed(1) + ' s'));
    const body = document.querySelector('#jobs tbody');
    const rows = body.querySelectorAll('tr.job');
    for (let i = 200; i < rows.length; i++) rows[i].remove();
    if (openJob === j.id) loadLog(j.id);
  }

  function toggleLog(id) {
    const old = byId('log-' + openJob);
    if (old) old.remove();
    const prev = byId('job-' + openJob);
    if (prev) prev.classList.remove('open');
    if (openJob === id) { openJob = null; return; }
    openJob = id;
    byId('job-' + id).classList.add('open');
    loadLog(id);
  }

  function loadLog(id) {
    fetch('/api/job/' + id).then((r) => r.json()).then((j) => {
      if (openJob !== id) return;
      let tr = byId('log-' + id);
      if (!tr) {
        tr = el('tr', 'log');
        tr.id = 'log-' + id;
        byId('job-' + id).after(tr);
      }
      const td = el('td');
      td.colSpan = 9;
      const decisions = j.decisions || [];
      if (j.decision_count > decisions.length)
        td.append(el('div', 'empty', (j.decision_count - decisions.length) + ' earlier decisions: cellctl job show ' + id));
      if (!decisions.length) td.append(el('div', 'empty', 'no decisions logged'));
      for (const d of decisions) {
        const div = el('div', 'dec');
        div.append(el('span', 'trig', time(d.time) + ' · op ' + d.op + ' · ' + d.trigger + ' → '));
        div.append(d.winner ? el('span', 'win', d.winner) : el('span', 'bad', 'waits'));
        div.append(document.createTextNode(': ' + d.why + (d.added_backlog_s ? ' (+' + d.added_backlog_s + ' s backlog)' : '')));
        const t = el('table');
        const h = el('tr');
        for (const x of ['station', 'online', 'fault', 'backlog', 'missing tools', 'eligible']) h.append(el('th', null, x));
        t.append(h);
        for (const c of d.considered) {
          const r = el('tr');
          r.append(el('td', null, c.station), el('td', c.online ? 'ok' : 'bad', c.online ? 'yes' : 'no'),
                   el('td', c.fault ? 'bad' : null, c.fault ? 'FAULT' : 'no'), el('td', null, dur(c.backlog_s)),
                   el('td', c.missing_tools.length ? 'bad' : null, c.missing_tools.join(', ') || '—'),
                   el('td', c.eligible ? 'ok' : 'bad', c.eligible ? 'yes' : 'no'));
          t.append(r);
        }
        div.append(t);
        td.append(div);
      }
      tr.replaceChildren(td);
    }).catch(() => {});
  }

  // ---- cycle times ----
  let cycleChart = null;
  const cycles = new Map();  // program -> [seconds]
  function addCycle(c) {
    if (!cycles.has(c.program)) cycles.set(c.program, []);
    cycles.get(c.program).push(c.s);
  }
  function renderCycles() {
    const body = document.querySelector('#cycletable tbody');
    body.replaceChildren();
    if (!cycles.size) { const r = el('tr'); const td = el('td', 'empty', 'no program finished yet'); td.colSpan = 6; r.append(td); body.append(r); }
    for (const [p, xs] of cycles) {
      const mean = xs.reduce((a, b) => a + b, 0) / xs.length;
      const r = el('tr');
      r.append(el('td', null, p), el('td', null, xs.length), el('td', null, xs[xs.length - 1].toFixed(1) + ' s'),
               el('td', null, mean.toFixed(1) + ' s'), el('td', null, Math.min(...xs).toFixed(1) + ' s'),
               el('td', null, Math.max(...xs).toFixed(1) + ' s'));
      body.append(r);
    }
    byId('cycles').parentElement.style.display = cycles.size ? '' : 'none';
    if (!HAS_CHART) return;
    const data = [...cycles].map(([p, xs], i) => ({
      label: p, data: xs.slice(-50).map((y, k) => ({ x: Math.max(0, xs.length - 50) + k + 1, y })),
      borderColor: AXIS_COLOURS[i % AXIS_COLOURS.length], backgroundColor: AXIS_COLOURS[i % AXIS_COLOURS.length],
      pointRadius: 3, borderWidth: 1.5,
    }));
    if (!cycleChart) {
      cycleChart = new Chart(byId('cycles'), {
        type: 'line', data: { datasets: data },
        options: {
          animation: false, responsive: true, maintainAspectRatio: false, parsing: false,
          plugins: { legend: { labels: { color: '#aab3bf', boxWidth: 10 } } },
          scales: {
            x: { type: 'linear', title: { display: true, text: 'run of the program', color: '#7d8794' }, ticks: { color: '#7d8794', precision: 0 }, grid: { color: '#262c34' } },
            y: { title: { display: true, text: 'machine seconds', color: '#7d8794' }, ticks: { color: '#7d8794' }, grid: { color: '#262c34' }, beginAtZero: true },
          },
        },
      });
    } else {
      cycleChart.data.datasets = data;
      cycleChart.update('none');
    }
  }

  // ---- inspection records ----
  function renderInspections() {
    const body = document.querySelector('#inspections tbody');
    body.replaceChildren();
    if (!S.inspections.length) { const r = el('tr'); const td = el('td', 'empty', 'no record yet'); td.colSpan = 7; r.append(td); body.append(r); }
    for (const x of S.inspections.slice(0, 12)) {
      const r = el('tr');
      r.dataset.name = x.name;
      const result = el('td');
      if (x.kind === 'run') {
        result.append(x.completed ? el('span', 'ok', 'completed') : el('span', 'bad', 'not completed'));
        if (x.reason) result.append(el('div', 'reason', x.reason));
      } else {
        result.append(el('span', null, x.name));
        if (x.excerpt) result.append(el('pre', 'excerpt', x.excerpt));
      }
      r.append(el('td', null, time(x.time)), el('td', null, x.station), el('td', null, x.pallet || '—'),
               el('td', null, x.job || '—'), el('td', null, (x.programs || []).join(', ') || '—'), result,
               el('td', null, x.kind === 'run' ? x.machine_s.toFixed(1) + ' s' : ''));
      body.append(r);
    }
  }

  // ---- program events (EVT) ----
  function renderProgramEvents() {
    const body = document.querySelector('#progevents tbody');
    body.replaceChildren();
    const evs = S.program_events || [];
    if (!evs.length) { const r = el('tr'); const td = el('td', 'empty', 'no event yet'); td.colSpan = 6; r.append(td); body.append(r); }
    for (const x of evs.slice(0, 12)) {
      const r = el('tr');
      r.append(el('td', null, time(x.time)), el('td', null, x.station), el('td', null, x.pallet || '—'),
               el('td', null, x.program), el('td', null, String(x.line)), el('td', null, x.text));
      body.append(r);
    }
  }

  // ---- DNC lines (cell/dnc/status): one row per station with a serial line; a line in error is red, and the
  // header names it so that it shows from anywhere on the page ----
  const dncLines = new Map();  // station -> row
  const DNC_WORDS = { idle: 'idle', sending: 'sending', receiving: 'receiving', dripping: 'dripping',
                      reading: 'program READ', writing: 'program WRITE',
                      error: 'ERROR', offline: 'no DNC process' };
  function num(n) { return Number(n).toLocaleString('en-US'); }
  // Byte counts: exact up to 100 kB (a program's size as the store shows it), in MB beyond (a drip feed).
  function size(n) { return n < 100000 ? num(n) + ' B' : (n / 1e6).toFixed(2) + ' MB'; }
  function dncProgress(d) {
    const cell = el('td', 'dnc-progress');
    if (!d.program) { cell.textContent = '—'; return cell; }
    if (d.total > 0) {
      const bar = el('div', 'bar');
      const fill = el('i');
      fill.style.width = Math.min(100, (100 * d.bytes) / d.total).toFixed(1) + '%';
      bar.append(fill);
      cell.append(bar, el('span', null, size(d.bytes) + ' of ' + size(d.total)));
    } else {
      cell.append(el('span', null, size(d.bytes)));
    }
    return cell;
  }
  function dncRow(d) {
    const r = el('tr', 'dnc-' + d.state);
    r.id = 'dnc-' + d.station;
    r.dataset.state = d.state;
    const line = el('td');
    line.append(el('span', 'dnc-state s-' + d.state, DNC_WORDS[d.state] || d.state), el('small', null, ' ' + d.device));
    const err = el('td', 'dnc-error-text', d.last_error || '—');
    if (d.last_error && !d.failed) err.classList.add('old');
    err.title = d.last_error || '';
    r.append(el('td', 'dnc-station', d.station), line, el('td', null, val(d.program)), dncProgress(d),
             el('td', null, d.rate > 0 ? num(Math.round(d.rate)) + ' B/s' : '—'),
             el('td', null, d.stopped_s.toFixed(1) + ' s'), el('td', null, String(d.stalls)),
             el('td', null, d.transfers + (d.errors ? ' (' + d.errors + ' failed)' : '')), err);
    return r;
  }
  // The station's card says it too (its kind row, which renderStation leaves alone): a transfer under way,
  // a line in error, a line without its process; nothing for an idle line.
  function dncMark(d) {
    const rec = stations.get(d.station);
    if (!rec) return;
    let mark = rec.el.dncMark;
    if (!mark) {
      mark = rec.el.dncMark = el('span', 'dncmark');
      rec.el.kindRow.insertBefore(mark, rec.el.pathBtn);
    }
    const pct = d.total > 0 ? ' ' + Math.floor((100 * d.bytes) / d.total) + '%' : '';
    const words = { error: 'DNC line error', offline: 'no DNC process', sending: 'DNC sending' + pct,
                    dripping: 'DNC dripping' + pct, receiving: 'DNC receiving', reading: 'DNC program READ' };
    mark.hidden = !words[d.state];
    mark.className = 'dncmark s-' + d.state;
    mark.textContent = words[d.state] || '';
    mark.title = d.state === 'error' ? d.last_error : d.program;
  }
  byId('dnc-alert').addEventListener('click', () => byId('dnc-row').scrollIntoView());
  function renderDnc() {
    byId('dnc-row').hidden = dncLines.size === 0;
    const body = document.querySelector('#dnc tbody');
    body.replaceChildren();
    const bad = [];
    for (const d of [...dncLines.values()].sort((a, b) => a.station.localeCompare(b.station))) {
      body.append(dncRow(d));
      dncMark(d);
      if (d.state === 'error') bad.push(d.station + ' line error');
      if (d.state === 'offline') bad.push(d.station + ' no DNC process');
    }
    const alert = byId('dnc-alert');
    alert.hidden = bad.length === 0;
    alert.textContent = 'DNC: ' + bad.join(' · ');
  }

  function renderServices() {
    const names = { 'cell-program-store': 'program store', 'cell-scheduler': 'scheduler', 'cell-inspection-writer': 'inspection writer' };
    const box = byId('services');
    box.replaceChildren();
    for (const [id, label] of Object.entries(names)) {
      const up = S.services[id];
      const s = el('span', 'svc ' + (up ? 'up' : 'off'), label + (up ? '' : ' offline'));
      s.dataset.service = id;
      box.append(s);
    }
  }

  let skew = 0;  // browser clock minus server clock, s
  function renderAll() {
    skew = Date.now() / 1000 - S.now;
    for (const st of S.stations) renderStation(st);
    for (const [id, a] of Object.entries(S.axes)) {
      const rec = stations.get(id);
      if (!rec) continue;
      rec.trail = [];
      a.t.forEach((t, i) => rec.trail.push([t, a.pos[i]]));
      if (a.t.length) pushAxes(id, a.t[a.t.length - 1], a.pos[a.pos.length - 1], a.feed, a.spindle_rpm, a.live_tool_rpm);
    }
    document.querySelector('#jobs tbody').replaceChildren();
    jobs.clear();
    for (const j of S.jobs) { jobs.set(j.id, j); }
    for (const j of [...S.jobs].reverse()) jobRow(j);
    cycles.clear();
    for (const c of S.cycles) addCycle(c);
    renderCycles();
    renderInspections();
    renderProgramEvents();
    renderServices();
    dncLines.clear();
    for (const d of S.dnc || []) dncLines.set(d.station, d);
    renderDnc();
    drawAxes();
  }

  // ---- the plan (Gantt chart): /api/plan every few seconds and soon after a job changes ----
  // One lane per station: the planned visits (the scheduler's projection: label pallet, route and operation)
  // and, below them, what actually ran; a red line at now; the waiting pallets listed with their reason.
  let plan = null;
  let planTimer = null;
  function ms(iso) { return iso ? Date.parse(iso) : null; }
  function planLabel(r) {
    return 'P' + r.pallet + (r.route ? ' ' + r.route : '') + ' op ' + r.op;
  }
  function planWindow(p, now) {
    let end = now;
    for (const r of p.planned) end = Math.max(end, ms(r.end));
    const ahead = Math.min(Math.max(end - now, 10 * 60e3), 12 * 3600e3);
    return [now - ahead / 3, now + ahead * 1.04];
  }
  function tickStep(span) {
    for (const m of [1, 2, 5, 10, 15, 30, 60, 120, 240]) if (span / (m * 60e3) <= 10) return m * 60e3;
    return 480 * 60e3;
  }
  function bar(track, cls, from, to, w, text, title) {
    const [a, b] = w;
    const l = Math.max(from, a), r = Math.min(to, b);
    if (r <= l) return;
    const e = el('div', 'gbar ' + cls, text);
    e.style.left = ((l - a) / (b - a) * 100) + '%';
    e.style.width = 'calc(' + ((r - l) / (b - a) * 100) + '% - 1px)';
    e.title = title;
    track.append(e);
  }
  function laneLabel(id, p) {
    const lab = el('div', 'glabel');
    lab.append(el('b', '', id));
    const cur = p.current && p.current[id], nxt = p.next && p.next[id];
    if (cur) lab.append(el('div', 'gnext', 'now: ' + planLabel(cur) + ' until ' + time(cur.end)));
    if (nxt) lab.append(el('div', 'gnext', 'next: ' + planLabel(nxt) + ' at ' + time(nxt.start)));
    if (!cur && !nxt) lab.append(el('div', '', 'nothing planned'));
    return lab;
  }
  function renderAxis(box, w) {
    const axis = el('div', 'gaxis');
    const step = tickStep(w[1] - w[0]);
    for (let t = Math.ceil(w[0] / step) * step; t < w[1]; t += step) {
      const tk = el('span', 'gtick', new Date(t).toLocaleTimeString([], { hour12: false, hour: '2-digit', minute: '2-digit' }));
      tk.style.left = ((t - w[0]) / (w[1] - w[0]) * 100) + '%';
      axis.append(tk);
    }
    box.append(axis);
    return step;
  }
  function renderLane(box, id, p, w, now, step) {
    const lane = el('div', 'glane');
    lane.id = 'lane-' + id;
    const track = el('div', 'gtrack');
    for (let t = Math.ceil(w[0] / step) * step; t < w[1]; t += step) {
      const g = el('div', 'gtickline');
      g.style.left = ((t - w[0]) / (w[1] - w[0]) * 100) + '%';
      track.append(g);
    }
    for (const r of p.planned.filter((x) => x.station === id)) {
      const a = ms(r.start), b = ms(r.end);
      const cur = a <= now && now < b;
      bar(track, cur ? 'now' : '', a, Math.max(b, a + 1000), w, planLabel(r),
          'job ' + r.job + ' · pallet ' + r.pallet + (r.route ? ' · route ' + r.route : '') + ' · op ' + r.op +
          '\nplanned ' + time(r.start) + ' – ' + time(r.end) + ' (' + dur((b - a) / 1000) + ')');
    }
    for (const r of p.ran.filter((x) => x.station === id)) {
      const a = ms(r.start), b = r.end ? ms(r.end) : now;
      bar(track, 'actual ' + (r.end ? r.state : 'running'), a, Math.max(b, a + 1000), w, 'P' + r.pallet + ' op ' + r.op,
          'ran: job ' + r.job + ' · pallet ' + r.pallet + ' · op ' + r.op + ' · ' + r.state +
          '\n' + time(r.start) + ' – ' + (r.end ? time(r.end) : 'now') + ' (' + dur((b - a) / 1000) + ')');
    }
    const line = el('div', 'gnow');
    line.style.left = ((now - w[0]) / (w[1] - w[0]) * 100) + '%';
    track.append(line);
    lane.append(laneLabel(id, p), track);
    box.append(lane);
  }
  function renderPlan() {
    const p = plan;
    const box = byId('gantt'), status = byId('planstatus'), waiting = byId('planwaiting');
    if (!p) return;
    const now = Date.now();
    const w = planWindow(p, now);
    box.replaceChildren();
    const step = renderAxis(box, w);
    // A lane for each station the cell runs (online) or that has a visit planned or run; the rest of the
    // configured stations are not in this cell.
    const used = new Set([...p.planned, ...p.ran].map((r) => r.station));
    const lanes = p.stations.filter((id) => used.has(id) || (stations.get(id) && stations.get(id).data.online));
    for (const id of lanes) renderLane(box, id, p, w, now, step);
    if (!lanes.length) box.append(el('div', 'empty', 'No station online and nothing planned'));
    status.className = 'planstatus' + (p.error ? ' bad' : '');
    status.textContent = p.error ? p.error + (p.fetched ? ' (plan of ' + time(p.fetched) + ')' : '')
                                 : 'planned at ' + time(p.fetched);
    waiting.replaceChildren();
    for (const r of p.waiting) {
      const d = el('div');
      d.append(el('b', '', 'Pallet ' + r.pallet + ' waits'),
               document.createTextNode(' (job ' + r.job + (r.route ? ', route ' + r.route : '') + ', op ' + r.op + '): ' + val(r.waiting_for)));
      waiting.append(d);
    }
  }
  function loadPlan() {
    fetch('/api/plan', { cache: 'no-store' })
      .then((r) => r.json())
      .then((p) => { plan = p; renderPlan(); })
      .catch(() => {});
  }
  function planSoon() {
    if (planTimer === null) planTimer = setTimeout(() => { planTimer = null; loadPlan(); }, 400);
  }

  function apply(ev) {
    switch (ev.type) {
      case 'station': renderStation(ev.station); break;
      case 'job': jobs.set(ev.job.id, ev.job); jobRow(ev.job); planSoon(); break;
      case 'axes': pushAxes(ev.station, ev.t, ev.pos, ev.feed, ev.spindle_rpm, ev.live_tool_rpm); break;
      case 'cycle': addCycle(ev.cycle); renderCycles(); break;
      case 'inspection':
        S.inspections = [ev.record, ...S.inspections.filter((x) => x.name !== ev.record.name)].slice(0, 50);
        renderInspections();
        break;
      case 'program_event':
        S.program_events = [ev.program_event, ...(S.program_events || [])].slice(0, 50);
        renderProgramEvents();
        break;
      case 'services': S.services = ev.services; renderServices(); break;
      case 'dnc': dncLines.set(ev.dnc.station, ev.dnc); renderDnc(); break;
    }
  }

  // ---- the live stream: EventSource reconnects by itself and resumes after Last-Event-ID ----
  const conn = byId('conn');
  let lostAt = null;
  function setLive(live) {
    if (live) { lostAt = null; conn.className = 'conn live'; conn.textContent = 'live'; return; }
    if (lostAt === null) lostAt = Date.now();
    conn.className = 'conn down';
    conn.textContent = 'connection lost: reconnecting (' + Math.round((Date.now() - lostAt) / 1000) + ' s)';
  }
  let es = null;
  function connect() {
    es = new EventSource('/api/events?after=' + S.event);
    es.onopen = () => setLive(true);
    es.onmessage = (m) => { const ev = JSON.parse(m.data); S.event = ev.id; apply(ev); };
    es.addEventListener('resync', (m) => { Object.assign(S, JSON.parse(m.data)); renderAll(); });
    es.onerror = () => {
      setLive(false);
      if (es.readyState === EventSource.CLOSED) { es.close(); setTimeout(connect, 1000); }
    };
  }

  renderAll();
  connect();
  loadPlan();
  setInterval(drawAxes, 500);
  setInterval(loadPlan, 3000);
  setInterval(() => {
    byId('clock').textContent = new Date().toLocaleTimeString([], { hour12: false });
    if (lostAt !== null) setLive(false);
  }, 1000);
})();
