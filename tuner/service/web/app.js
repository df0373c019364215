// The ftctune dashboard: the jobs list, a job's page and the submit form, over the documented
// API only (docs/service.md). Every text that comes from a job or the store is put into the page
// as text (textContent, text nodes), never as markup; the token, when the service has one, is
// sent as an Authorization header and kept in sessionStorage (gone with the tab).
'use strict';

const TOKEN_KEY = 'ftctune-token';
const PAGE_SIZE = 50;
const TRIAL_ROWS_SHOWN = 1000;

// ---------------------------------------------------------------------------------------------
// Small helpers

// An element with properties and children; strings become text nodes (never parsed as HTML).
function el(tag, props, ...children) {
  const e = document.createElement(tag);
  if (props) {
    for (const [k, v] of Object.entries(props)) {
      if (v === undefined || v === null || v === false) continue;
      if (k === 'class') e.className = v;
      else if (k === 'text') e.textContent = v;
      else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
      else e.setAttribute(k, v === true ? '' : String(v));
    }
  }
  for (const c of children.flat(Infinity)) {
    if (c === null || c === undefined || c === false) continue;
    e.appendChild(typeof c === 'string' || typeof c === 'number' ? document.createTextNode(String(c)) : c);
  }
  return e;
}

function clear(node) {
  while (node.firstChild) node.removeChild(node.firstChild);
  return node;
}

function fmt(v, digits = 6) {
  if (v === null || v === undefined || v === '') return '–';
  const n = Number(v);
  if (!Number.isFinite(n)) return String(v);
  return Number(n.toPrecision(digits)).toString();
}

function seconds(iso) {
  if (!iso) return NaN;
  const t = Date.parse(iso);
  return Number.isFinite(t) ? t / 1000 : NaN;
}

function duration(s) {
  if (!Number.isFinite(s) || s < 0) return '–';
  if (s < 60) return s.toFixed(1) + ' s';
  if (s < 3600) return Math.floor(s / 60) + ' min ' + Math.round(s % 60) + ' s';
  return Math.floor(s / 3600) + ' h ' + Math.round((s % 3600) / 60) + ' min';
}

function whenText(iso) {
  return iso ? iso.replace('T', ' ').replace(/\.\d+Z$/, ' UTC') : '–';
}

function jobDuration(j) {
  const start = seconds(j.started_at);
  const end = j.finished_at ? seconds(j.finished_at) : Date.now() / 1000;
  return duration(end - start);
}

// The time left, from the evaluations done since the job started (as `submit --wait` says it).
function etaText(j) {
  const p = j.progress;
  if (j.status !== 'running' || !p) return '';
  // Past its last iteration: the comparison and the noise floor, not an ETA of 0.
  if (p.phase === 'finishing') return 'comparing controllers and measuring the noise floor';
  if (!p.evaluations) return '';
  const elapsed = Date.now() / 1000 - seconds(j.started_at);
  if (!Number.isFinite(elapsed) || elapsed <= 0) return '';
  return 'ETA ' + duration(elapsed * (p.total_evaluations - p.evaluations) / p.evaluations);
}

function isFinished(status) {
  return status === 'succeeded' || status === 'failed' || status === 'cancelled';
}

// ---------------------------------------------------------------------------------------------
// The API

class ApiError extends Error {
  constructor(status, body) {
    super(body && body.error ? body.error.message : 'HTTP ' + status);
    this.status = status;
    this.body = body;
  }
}

function headers(extra) {
  const h = Object.assign({}, extra || {});
  const token = sessionStorage.getItem(TOKEN_KEY);
  if (token) h['Authorization'] = 'Bearer ' + token;
  return h;
}

async function request(path, options = {}) {
  const res = await fetch(path, Object.assign({}, options, {
    headers: headers(options.headers), credentials: 'omit', cache: 'no-store'}));
  if (res.status === 401) {
    askToken();
    throw new ApiError(401, null);
  }
  return res;
}

async function apiJson(path, options) {
  const res = await request(path, options);
  const text = await res.text();
  let body = null;
  try { body = text ? JSON.parse(text) : null; } catch (e) { body = null; }
  if (!res.ok) throw new ApiError(res.status, body);
  return body;
}

async function apiText(path) {
  const res = await request(path);
  const text = await res.text();
  if (!res.ok) {
    let body = null;
    try { body = JSON.parse(text); } catch (e) { body = null; }
    throw new ApiError(res.status, body);
  }
  return text;
}

// Downloads through fetch (so the token goes as a header), saved under `name`.
async function download(path, name) {
  const res = await request(path);
  if (!res.ok) {
    let body = null;
    try { body = await res.json(); } catch (e) { body = null; }
    throw new ApiError(res.status, body);
  }
  const url = URL.createObjectURL(await res.blob());
  const a = el('a', {href: url, download: name});
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

function askToken() {
  if (document.getElementById('token-form')) return;
  live.stop();
  const input = el('input', {type: 'password', id: 'token', autocomplete: 'off', size: 40});
  const form = el('form', {id: 'token-form', onsubmit: (ev) => {
    ev.preventDefault();
    sessionStorage.setItem(TOKEN_KEY, input.value.trim());
    live.start();
    route();
  }},
  el('h2', {text: 'This service needs a token'}),
  el('p', {text: 'It is sent as an Authorization header with each request and kept in this tab only (sessionStorage).'}),
  input, ' ', el('button', {type: 'submit', text: 'Use the token'}));
  clear(document.getElementById('main')).appendChild(form);
  input.focus();
}

function showError(container, e) {
  const box = el('div', {class: 'error'});
  if (e instanceof ApiError && e.status === 401) return;
  box.appendChild(document.createTextNode(e.message || String(e)));
  const details = e.body && e.body.error && Array.isArray(e.body.error.details) ? e.body.error.details : [];
  if (details.length) box.appendChild(errorList(details));
  container.appendChild(box);
}

// Each error at its JSON path.
function errorList(details) {
  return el('ul', {class: 'errors'}, details.map((d) =>
    el('li', {class: 'json-error'}, el('code', {class: 'path', text: d.path || '/'}), ' ',
       el('span', {class: 'message', text: d.message || ''}))));
}

// ---------------------------------------------------------------------------------------------
// Live updates: one event stream per tab (GET /v1/events), read through fetch so that the token
// goes as a header; views subscribe to it.

const live = {
  listeners: new Set(),
  controller: null,
  retry: 1000,
  running: false,

  on(fn) { this.listeners.add(fn); return () => this.listeners.delete(fn); },

  indicator(on, text) {
    const badge = document.getElementById('live');
    if (!badge) return;
    badge.textContent = text;
    badge.classList.toggle('on', on);
  },

  generation: 0,

  start() {
    if (this.running) return;
    this.running = true;
    this.connect(++this.generation);
  },

  stop() {
    this.running = false;
    this.generation++;
    if (this.controller) this.controller.abort();
    this.indicator(false, 'paused');
  },

  async connect(generation) {
    const mine = () => this.running && generation === this.generation;
    while (mine()) {
      this.controller = new AbortController();
      try {
        const res = await fetch('/v1/events', {headers: headers(), signal: this.controller.signal,
                                               credentials: 'omit', cache: 'no-store'});
        if (res.status === 401) { askToken(); return; }
        if (!res.ok || !res.body) throw new Error('HTTP ' + res.status);
        this.indicator(true, 'live');
        this.retry = 1000;
        // Changes missed while disconnected: the views read their state again.
        this.emit({type: 'open'});
        const reader = res.body.getReader();
        const decoder = new TextDecoder();
        let buffer = '';
        for (;;) {
          const {value, done} = await reader.read();
          if (done) break;
          buffer += decoder.decode(value, {stream: true});
          let end;
          while ((end = buffer.indexOf('\n\n')) >= 0) {
            this.parse(buffer.slice(0, end));
            buffer = buffer.slice(end + 2);
          }
        }
      } catch (e) {
        if (!mine()) return;
      }
      if (!mine()) return;
      this.indicator(false, 'reconnecting');
      await new Promise((r) => setTimeout(r, this.retry));
      this.retry = Math.min(this.retry * 2, 15000);
    }
  },

  parse(block) {
    let type = 'message';
    const data = [];
    for (const line of block.split('\n')) {
      if (line.startsWith('event: ')) type = line.slice(7);
      else if (line.startsWith('data: ')) data.push(line.slice(6));
    }
    if (!data.length) return;
    let payload;
    try { payload = JSON.parse(data.join('\n')); } catch (e) { return; }
    this.emit({type, data: payload});
  },

  emit(event) {
    for (const fn of [...this.listeners]) {
      try { fn(event); } catch (e) { console.error(e); }
    }
  },
};

// Calls fn at most once per `ms`, the last call winning.
function throttle(fn, ms) {
  let timer = null, last = 0;
  return () => {
    const wait = Math.max(0, last + ms - Date.now());
    if (timer) return;
    timer = setTimeout(() => { timer = null; last = Date.now(); fn(); }, wait);
  };
}

// Chart.js (Debian's, served from the binary) is loaded by the first job page only: the jobs
// list does not wait for its 200 kB.
let chartLib = null;
function chartJs() {
  if (!chartLib) {
    chartLib = new Promise((resolve, reject) => {
      if (window.Chart) return resolve(window.Chart);
      document.head.appendChild(el('script', {src: '/ui/chart.min.js',
        onload: () => resolve(window.Chart), onerror: () => reject(new Error('Chart.js did not load'))}));
    });
  }
  return chartLib;
}

// The metrics a run records (GET /v1/metrics: the service's metrics record), asked once: the
// comparison's columns are those comparison.md tabulates, named and united as the service says.
let metricList = null;
function metrics() {
  if (!metricList) metricList = apiJson('/v1/metrics').then((m) => m.metrics).catch((e) => {
    metricList = null;  // asked again next time (a token entered meanwhile)
    throw e;
  });
  return metricList;
}

// ---------------------------------------------------------------------------------------------
// Views. Each returns a cleanup function (unsubscribes, destroys charts).

let cleanup = null;

function route() {
  if (cleanup) { cleanup(); cleanup = null; }
  const main = clear(document.getElementById('main'));
  const hash = location.hash || '#/';
  let m;
  if ((m = hash.match(/^#\/job\/([0-9a-f]{1,32})$/))) cleanup = jobView(main, m[1]);
  else if (hash === '#/submit') cleanup = submitView(main);
  else cleanup = jobsView(main);
}

// A job's best so far: its J, or for a front (two or more soft goals) its size, which one J (a
// corner of the front) would misname.
function frontOf(p) {
  return p && p.best && p.best.front ? p.best.front : null;
}
function bestText(p) {
  const f = frontOf(p);
  if (f) return 'front: ' + f.points + ' point' + (f.points === 1 ? '' : 's') + ' so far';
  return fmt(p.best_fitness);
}

// A finished run's state; a run that succeeded with warnings in its gains file (a tuned value at
// a bound, a loop that saturates or never settles, a margin inside the noise floor) says so.
function stateBadge(status, warnings) {
  if (status === 'succeeded' && warnings > 0)
    return el('span', {class: 'state succeeded warned', title: warnings + ' warning' +
      (warnings === 1 ? '' : 's') + ': see the notes under Results', text: 'succeeded with warnings'});
  return el('span', {class: 'state ' + status, text: status});
}

function progressCell(j) {
  const p = j.progress;
  const bar = el('progress', {max: p.total_evaluations || 1, value: p.evaluations || 0});
  const text = p.evaluations + '/' + p.total_evaluations;
  const eta = etaText(j);
  return [bar, ' ', el('span', {class: 'progress-text', text: eta ? text + ' · ' + eta : text})];
}

function jobsView(main) {
  let offset = 0;
  let rows = new Map();
  const name = el('input', {type: 'search', id: 'filter-name', placeholder: 'name contains…', size: 24});
  const status = el('select', {id: 'filter-status'},
    ['', 'queued', 'running', 'succeeded', 'failed', 'cancelled'].map((s) =>
      el('option', {value: s, text: s || 'any state'})));
  const prev = el('button', {text: '‹ newer', id: 'page-prev'});
  const next = el('button', {text: 'older ›', id: 'page-next'});
  const count = el('span', {id: 'jobs-count'});
  const tbody = el('tbody');
  const COLUMNS = ['Name', 'State', 'Progress', 'Best J (or front)', 'Submitted', 'Duration', 'Id'];
  const table =
      el('table', {id: 'jobs-table'},
         el('thead', null, el('tr', null, COLUMNS.map((h) => el('th', {text: h})))), tbody);
  const message = el('div');
  main.append(el('h1', {text: 'Jobs'}),
              el('div', {class: 'toolbar'}, name, status, prev, next, count), message, table);

  const shown = new Map();  // id → the job as last seen
  function fill(row, j) {
    shown.set(j.id, j);
    clear(row);
    row.append(
        el('td', null, el('a', {href: '#/job/' + j.id, class: 'job-link', text: j.name})),
        el('td', null, stateBadge(j.status, j.warnings)),
        el('td', {class: 'progress'}, progressCell(j)),
        el('td', {class: 'num best', text: bestText(j.progress)}),
        el('td', {text: whenText(j.created_at)}),
        el('td', {class: 'num', text: j.started_at ? jobDuration(j) : '–'}),
        el('td', null, el('code', {text: j.id})));
  }

  async function load() {
    const q = new URLSearchParams({limit: PAGE_SIZE, offset});
    if (status.value) q.set('status', status.value);
    if (name.value) q.set('name', name.value);
    try {
      const page = await apiJson('/v1/jobs?' + q.toString());
      clear(message);
      rows = new Map();
      shown.clear();
      clear(tbody);
      // Grouped by what J measures, each group under its measure, in the order of its newest
      // job: a J of the post-fault ISE and one of a CVaR over an ensemble are not set side by
      // side as if they compared.
      const groups = new Map();
      for (const j of page.jobs) {
        const key = j.objective || '';
        if (!groups.has(key)) groups.set(key, []);
        groups.get(key).push(j);
      }
      for (const [objective, jobs] of groups) {
        tbody.appendChild(el(
            'tr', {class: 'group', 'data-objective': objective},
            el('td', {colspan: COLUMNS.length},
               objective ? 'J = ' + objective : 'J: not recorded (a job stored by an older server)',
               el('span', {
                 class: 'group-count',
                 text: ' · ' + jobs.length + ' job' + (jobs.length === 1 ? '' : 's')
               }))));
        for (const j of jobs) {
          const row = el('tr', {'data-id': j.id});
          fill(row, j);
          rows.set(j.id, row);
          tbody.appendChild(row);
        }
      }
      count.textContent = page.total === 0 ? 'no jobs'
        : (offset + 1) + '–' + (offset + page.jobs.length) + ' of ' + page.total;
      prev.disabled = offset === 0;
      next.disabled = offset + page.jobs.length >= page.total;
    } catch (e) {
      clear(message);
      showError(message, e);
    }
  }
  const reload = throttle(load, 500);
  prev.addEventListener('click', () => { offset = Math.max(0, offset - PAGE_SIZE); load(); });
  next.addEventListener('click', () => { offset += PAGE_SIZE; load(); });
  status.addEventListener('change', () => { offset = 0; load(); });
  let typing = null;
  name.addEventListener('input', () => { clearTimeout(typing); typing = setTimeout(() => { offset = 0; load(); }, 250); });

  const off = live.on((ev) => {
    if (ev.type === 'open' || ev.type === 'deleted') return reload();
    if (ev.type !== 'job') return;
    const j = ev.data;
    const row = rows.get(j.id);
    const filtered = (status.value && status.value !== j.status) || (name.value && !j.name.includes(name.value));
    if (row && !filtered) fill(row, j);
    else if (row || (!filtered && offset === 0)) reload();  // a new job, or one that left the filter
  });
  // Durations and ETAs of running jobs move with the clock (from what the page holds: no
  // request).
  const tick = setInterval(() => {
    for (const [id, row] of rows) {
      const j = shown.get(id);
      if (j && j.status === 'running') fill(row, j);
    }
  }, 1000);
  load();
  return () => { off(); clearInterval(tick); };
}

// An axis title: its label, and whether the axis is logarithmic.
function axisTitle(label, logarithmic) {
  return label + (logarithmic ? ' (log scale)' : '');
}

// A colour for an objective between lo and hi (log scale): blue for the best, red for the worst.
function colour(v, lo, hi) {
  if (!Number.isFinite(v)) return 'rgba(120,120,120,0.5)';
  const t = hi > lo ? (Math.log(v) - Math.log(lo)) / (Math.log(hi) - Math.log(lo)) : 0;
  const hue = 240 * (1 - Math.min(1, Math.max(0, t)));
  return 'hsla(' + hue.toFixed(0) + ',75%,45%,0.75)';
}

function parseCsv(text) {
  const lines = text.split('\n').filter((l) => l.length);
  if (!lines.length) return {columns: [], rows: []};
  const columns = lines[0].split(',');
  const rows = lines.slice(1).map((l) => l.split(','));
  return {columns, rows};
}

// Conditions like `Kp>10, diverged=0` (all must hold), or text any cell contains.
function rowFilter(text, columns) {
  const parts = text.split(',').map((s) => s.trim()).filter((s) => s);
  const tests = parts.map((p) => {
    const m = p.match(/^([A-Za-z_][\w.]*)\s*(<=|>=|!=|<|>|=)\s*(.+)$/);
    const col = m ? columns.indexOf(m[1]) : -1;
    if (col < 0) return (row) => row.some((c) => c.includes(p));
    const v = Number(m[3]);
    const ops = {'<': (a) => a < v, '>': (a) => a > v, '<=': (a) => a <= v, '>=': (a) => a >= v,
                 '=': (a) => a === v, '!=': (a) => a !== v};
    return (row) => ops[m[2]](Number(row[col] === '' ? NaN : row[col]));
  });
  return (row) => tests.every((t) => t(row));
}

function jobView(main, id) {
  const charts = [];
  let job = null;
  let warnings = 0;  // the finished run's gains.json warnings, once its results are loaded
  let trials = {columns: [], rows: []};
  let sort = {col: -1, dir: 1};
  let history = [];

  const header = el('div');
  const actions = el('div', {class: 'toolbar', id: 'job-actions'});
  const notes = el('div', {id: 'job-notes'});
  const convergence = el('canvas', {id: 'convergence', 'data-points': 0});
  const scatter = el('canvas', {id: 'scatter', 'data-points': 0});
  const xSel = el('select', {id: 'scatter-x'});
  const ySel = el('select', {id: 'scatter-y'});
  // The colour scale of the trial scatter: the objective's lowest (blue) to highest (red) on a
  // log scale, as colour() maps them.
  const scaleBar = el('canvas', {id: 'scatter-scale-bar', width: 220, height: 12});
  const scaleLo = el('span', {id: 'scatter-scale-lo'}),
        scaleHi = el('span', {id: 'scatter-scale-hi'});
  const scaleText = el('span', {id: 'scatter-scale-text'});
  const trialFilter = el('input', {type: 'search', id: 'trials-filter', size: 40,
                                   placeholder: 'Kp>10, diverged=0  or any text'});
  const trialCount = el('span', {id: 'trials-count'});
  const trialHead = el('thead');
  const trialBody = el('tbody');
  const comparison = el('div', {id: 'comparison'});
  const figures = el('div', {id: 'figures'});
  const frontBox = el('div', {id: 'front'});
  const downloads = el('div', {class: 'toolbar', id: 'downloads'});
  const message = el('div');

  main.append(
      header, actions, message, notes,
      el('div', {class: 'charts'},
         el('div', null,
            el('h3', {id: 'convergence-title', text: 'Convergence: best J per iteration'}),
            el('div', {class: 'chart-box'}, convergence)),
         el('div', null, el('h3', {text: 'Trials: parameters coloured by objective'}),
            el('div', {class: 'toolbar'}, 'x ', xSel, ' y ', ySel),
            el('div', {class: 'chart-box'}, scatter),
            el('div', {class: 'toolbar colour-scale', id: 'scatter-scale'}, scaleText, scaleLo,
               scaleBar, scaleHi))),
      el('h3', {text: 'Trials'}), el('div', {class: 'toolbar'}, trialFilter, trialCount),
      el('div', {class: 'scroll'}, el('table', {id: 'trials-table'}, trialHead, trialBody)),
      el('h3', {text: 'Comparison'}), comparison, frontBox, figures, el('h3', {text: 'Downloads'}),
      downloads);

  let convChart = null, scatterChart = null;
  const makeCharts = (Chart) => {
    convChart = new Chart(convergence, {
      type: 'line',
      data: {datasets: [{label: 'best J', data: [], borderColor: '#2980b9', backgroundColor: '#2980b9',
                         pointRadius: 2, tension: 0}]},
      options: {animation: false, maintainAspectRatio: false, parsing: false,
                scales: {x: {type: 'linear', title: {display: true, text: 'iteration'}},
                         y: {title: {display: true, text: 'best fitness J'}}},
                plugins: {legend: {display: false}}},
    });
    charts.push(convChart);
    scatterChart = new Chart(scatter, {
      type: 'scatter',
      data: {datasets: [{label: 'trials', data: [], pointBackgroundColor: [], pointRadius: 3}]},
      options: {animation: false, maintainAspectRatio: false,
                plugins: {legend: {display: false},
                          tooltip: {callbacks: {label: (c) => 'J = ' + fmt(c.raw.objective)}}},
                scales: {x: {title: {display: true, text: ''}}, y: {title: {display: true, text: ''}}}},
    });
    charts.push(scatterChart);
    renderConvergence();
    renderScatter();
  };

  function renderHeader() {
    clear(header);
    const p = job.progress;
    // A front has no best J: the history's J is one corner of it (the least first soft goal).
    if (frontOf(p)) {
      const title = document.getElementById('convergence-title');
      if (title) title.textContent = 'Convergence: J of the trial with the least first soft goal ' +
        '(one corner of the front; history.csv has the hypervolume per iteration)';
    }
    header.append(
      el('h1', null, job.name + ' ', stateBadge(job.status, warnings)),
      el('dl', {class: 'meta'},
        el('dt', {text: 'id'}), el('dd', null, el('code', {text: job.id})),
        el('dt', {text: 'progress'}), el('dd', {id: 'job-progress'}, progressCell(job),
          p.iteration === null ? '' : ' · iteration ' + p.iteration + '/' + p.iterations),
        el('dt', {text: frontOf(p) ? 'front so far' : 'best J'}),
        el('dd', {id: 'job-best', text: frontOf(p) ? bestText(p) : fmt(p.best_fitness) +
          (p.best && Object.keys(p.best).length ? '  (' + Object.entries(p.best)
            .map(([k, v]) => k + ' = ' + fmt(v, 5)).join(', ') + ')' : '')}),
        el('dt', {text: 'submitted'}), el('dd', {text: whenText(job.created_at)}),
        el('dt', {text: 'started'}), el('dd', {text: whenText(job.started_at)}),
        el('dt', {text: 'finished'}), el('dd', {text: whenText(job.finished_at)}),
        el('dt', {text: 'duration'}), el('dd', {text: job.started_at ? jobDuration(job) : '–'}),
        job.error ? [el('dt', {text: 'error'}), el('dd', {class: 'job-error', text: job.error})] : []));
    // The buttons stay as they are (an open confirmation included) until the state changes.
    const key = job.status + '/' + job.cancel_requested;
    if (key !== actionsKey && !confirming) renderActions();
  }
  let actionsKey = null, confirming = false;

  // Cancel and delete, each after a confirmation on the page.
  function renderActions() {
    clear(actions);
    confirming = false;
    actionsKey = job.status + '/' + job.cancel_requested;
    const act = (label, question, cls, fn) => {
      const b = el('button', {class: cls, text: label, id: 'action-' + label.toLowerCase()});
      b.addEventListener('click', () => {
        clear(actions);
        confirming = true;
        actions.append(el('span', {class: 'confirm'}, question,
          el('button', {class: 'danger', id: 'confirm-yes', text: 'Yes, ' + label.toLowerCase(),
                        onclick: async () => {
                          try { await fn(); } catch (e) { showError(message, e); }
                          renderActions();
                        }}),
          el('button', {id: 'confirm-no', text: 'No', onclick: renderActions})));
      });
      actions.appendChild(b);
    };
    if (job.status === 'queued' || (job.status === 'running' && !job.cancel_requested))
      act('Cancel', 'Cancel this job? A running job stops before its next pack of simulations and keeps the results of its finished iterations.', '',
          async () => { job = await apiJson('/v1/jobs/' + id + '/cancel', {method: 'POST'}); renderHeader(); });
    if (isFinished(job.status))
      act('Delete', 'Delete this job and all its results from the service? This cannot be undone.', 'danger',
          async () => { await apiJson('/v1/jobs/' + id, {method: 'DELETE'}); location.hash = '#/'; });
    if (job.cancel_requested && job.status === 'running')
      actions.appendChild(el('span', {class: 'note', text: 'Cancelling: it stops before its next pack of simulations.'}));
  }

  function renderConvergence() {
    if (!convChart) return;
    const points = history.filter((h) => h.best_fitness !== null)
      .map((h) => ({x: h.iteration, y: h.best_fitness}));
    convChart.data.datasets[0].data = points;
    convChart.update('none');
    convergence.setAttribute('data-points', points.length);
  }

  // The search space's scales (the stored job's tuning parameters): a parameter searched on a log
  // scale is drawn on a log axis.
  let scales = {};
  async function loadScales() {
    try {
      const stored = await apiJson('/v1/jobs/' + id + '/job');
      const params = (stored.tuning && stored.tuning.parameters) || {};
      scales = {};
      for (const [n, v] of Object.entries(params))
        scales[n] = v && !Array.isArray(v) && v.scale === 'log' ? 'log' : 'linear';
      renderScatter();
    } catch (e) { /* linear axes */
    }
  }

  function drawScaleBar(lo, hi) {
    const ctx = scaleBar.getContext('2d');
    const w = scaleBar.width, h = scaleBar.height;
    for (let i = 0; i < w; ++i) {
      ctx.fillStyle = colour(Math.pow(10, i / (w - 1)), 1, 10);
      ctx.fillRect(i, 0, 1, h);
    }
    const shown = Number.isFinite(lo) && Number.isFinite(hi);
    scaleLo.textContent = shown ? fmt(lo, 3) : '';
    scaleHi.textContent = shown ? fmt(hi, 3) : '';
    scaleText.textContent =
        shown ? 'colour: objective J (log scale, lowest blue, highest red; grey: none)' : '';
    scaleBar.dataset.lo = shown ? String(lo) : '';
    scaleBar.dataset.hi = shown ? String(hi) : '';
  }

  function renderScatter() {
    if (!scatterChart) return;
    const xi = trials.columns.indexOf(xSel.value), yi = trials.columns.indexOf(ySel.value);
    const oi = trials.columns.indexOf('objective');
    if (xi < 0 || yi < 0) return;
    const objectives = trials.rows.map((r) => Number(r[oi])).filter((v) => Number.isFinite(v) && v > 0);
    const lo = Math.min(...objectives), hi = Math.max(...objectives);
    const data = trials.rows.map((r) => ({x: Number(r[xi]), y: Number(r[yi]), objective: Number(r[oi])}));
    scatterChart.data.datasets[0].data = data;
    scatterChart.data.datasets[0].pointBackgroundColor = data.map((d) => colour(d.objective, lo, hi));
    const axis = (name) => (scales[name] === 'log' ? 'logarithmic' : 'linear');
    scatterChart.options.scales.x.type = axis(xSel.value);
    scatterChart.options.scales.y.type = axis(ySel.value);
    scatterChart.options.scales.x.title.text =
        axisTitle(xSel.value, axis(xSel.value) === 'logarithmic');
    scatterChart.options.scales.y.title.text =
        axisTitle(ySel.value, axis(ySel.value) === 'logarithmic');
    scatterChart.update('none');
    scatter.setAttribute('data-points', data.length);
    drawScaleBar(lo, hi);
  }

  function renderTrials() {
    const cols = trials.columns;
    if (!trialHead.firstChild || trialHead.firstChild.children.length !== cols.length) {
      clear(trialHead).appendChild(el('tr', null, cols.map((c, i) =>
        el('th', {class: 'sortable', text: c, title: 'sort by ' + c, onclick: () => {
          sort = {col: i, dir: sort.col === i ? -sort.dir : 1};
          renderTrials();
        }}))));
      // The scatter's axes: the parameters (the columns between index and objective).
      const params = cols.slice(2, cols.indexOf('objective'));
      for (const [sel, pick] of [[xSel, 0], [ySel, 1]]) {
        clear(sel);
        for (const p of params) sel.appendChild(el('option', {value: p, text: p}));
        sel.value = params[Math.min(pick, params.length - 1)] || '';
      }
    }
    const keep = rowFilter(trialFilter.value, cols);
    let rows = trials.rows.filter(keep);
    if (sort.col >= 0) {
      const c = sort.col, d = sort.dir;
      rows = rows.slice().sort((a, b) => {
        const x = Number(a[c]), y = Number(b[c]);
        if (Number.isNaN(x) || Number.isNaN(y)) return d * String(a[c]).localeCompare(String(b[c]));
        return d * (x - y);
      });
    }
    const accepted = cols.indexOf('accepted');
    // A capped trial's objective, goals and violation are lower bounds (issue 27): shown as
    // "≥ bound" (a goal without a bound is empty).
    const capped = cols.indexOf('capped');
    const bounded = new Set(cols.map((c, i) =>
      c === 'objective' || c === 'violation' || /^goal[0-9]+_/.test(c) ? i : -1));
    clear(trialBody);
    for (const r of rows.slice(0, TRIAL_ROWS_SHOWN))
      trialBody.appendChild(el('tr', {class: r[accepted] === '1' ? 'accepted' : ''},
        r.map((c, i) => {
          // Six significant digits (the file keeps 17; the cell's title has them).
          // (An integer, such as an index, as it is.)
          const shown = c === '' || /^-?[0-9]+$/.test(c) || Number.isNaN(Number(c)) ? c : fmt(c);
          return el('td', {class: 'num', title: shown === c ? '' : c,
            text: bounded.has(i) && c !== '' && capped >= 0 && r[capped] === '1' ? '≥ ' + shown : shown});
        })));
    trialCount.textContent = rows.length + ' of ' + trials.rows.length + ' trials' +
      (rows.length > TRIAL_ROWS_SHOWN ? ' (the first ' + TRIAL_ROWS_SHOWN + ' shown)' : '');
  }
  trialFilter.addEventListener('input', renderTrials);
  xSel.addEventListener('change', renderScatter);
  ySel.addEventListener('change', renderScatter);

  async function loadProgress() {
    if (job.progress.iteration === null) return;
    try {
      const [h, t] = await Promise.all([apiJson('/v1/jobs/' + id + '/history?format=json'),
                                        apiText('/v1/jobs/' + id + '/trials')]);
      history = h;
      trials = parseCsv(t);
      renderConvergence();
      renderTrials();
      renderScatter();
    } catch (e) {
      if (!(e instanceof ApiError && e.status === 409)) showError(message, e);
    }
  }

  function renderComparison(c, gains, recorded) {
    clear(comparison);
    clear(notes);
    if (job.partial)
      notes.appendChild(el('div', {class: 'note', text:
        'These are the results of the iterations run so far: gains.json records optimizer.completed false, which the gains loader refuses.'}));
    if (!c) {
      comparison.appendChild(el('p', {text: 'The comparison exists once the job has finished.'}));
      return;
    }
    if (c.noise_floor) notes.appendChild(el('p', {class: 'noise-floor', text: c.noise_floor}));
    for (const w of (gains && gains.warnings) || [])
      notes.appendChild(el('div', {class: 'note bound-warning', text: w}));
    const scenarios = c.scenarios || [];
    // What the controller read in each scenario with sensors (noise, bias, delay, acceleration).
    for (const s of scenarios)
      if (c.sensors && c.sensors[s])
        notes.appendChild(el('p', {class: 'sensors', text: 'Sensors of scenario ' + s + ': ' + c.sensors[s] + '.'}));
    // One column per tabled metric and scenario; a fault metric's cell holds one value per onset.
    const columns = recorded.filter((m) => m.in_tables);
    const cell = (v) => (Array.isArray(v) ? v.map((x) => fmt(x)).join(' / ') : fmt(v));
    const head = ['controller', 'role', 'objective', 'fitness'];
    for (const s of scenarios)
      for (const m of columns) head.push(s + ': ' + m.label + ' [' + m.unit + ']');
    comparison.appendChild(el('div', {class: 'scroll'}, el('table', {id: 'comparison-table'},
      el('thead', null, el('tr', null, head.map((h) => el('th', {text: h})))),
      el('tbody', null, (c.controllers || []).map((k) => el('tr', null,
        el('td', {class: 'label', text: k.label}), el('td', {text: k.role}),
        el('td', {class: 'num', text: fmt(k.objective)}),
        // A controller that breaks a hard goal has no fitness to compare (its negative value
        // only orders the infeasible ones): say so, with its violation.
        el('td', {class: 'num', text: k.goals && k.goals.feasible === false
          ? 'infeasible (violation ' + fmt(k.goals.total_violation, 3) + ')' : fmt(k.fitness)}),
        scenarios.map((s, i) => columns.map((m) => el('td', {class: 'num', 'data-metric': m.name,
          text: cell(k.scenarios && k.scenarios[i] ? k.scenarios[i][m.name] : null)})))))))));
  }

  // The Pareto front of a job with two or more soft goals (front.json): its first two soft goals,
  // the picked point circled, the compared controllers marked, and as report.html draws them
  // (tuner/report/front_figures.cpp): each point's noise floor f (SPEC 14, the relative spread of
  // its nudged copies) as a band of width f·|v| centred on the value on each axis, and a dashed
  // link between two points that are no trade-off (each point's within_noise partners, by the
  // run's rule). A table lists every point with its floors and partners. The goals are named by
  // front.json's labels and units. Log axes where every value is positive and they span a decade.
  // A click on a point (or its row's button) downloads its gains file (pickPoint).
  let frontChart = null;
  function renderFront(front) {
    heldOutView = null;
    clear(frontBox);
    if (frontChart) { frontChart.destroy(); frontChart = null; }
    const soft = front.goals.map((g, i) => (g.minimize ? i : -1)).filter((i) => i >= 0);
    if (soft.length < 2) return;
    const [a, b] = soft;
    // A front.json written before the labels and partners (docs/usage.md): the metric's name, no
    // partners.
    const name = (g) => (g.label || g.metric) + (g.unit ? ' [' + g.unit + ']' : '');
    const finite = (v) => typeof v === 'number' && Number.isFinite(v);
    const drawable = (g) => finite(g[a]) && finite(g[b]);
    // Each drawn point keeps its index in front.json (the rule index:K picks it).
    const points = front.points.map((p, k) => ({x: p.goals[a], y: p.goals[b], point: k}))
                       .filter((p) => finite(p.x) && finite(p.y));
    const all = points.concat(front.compared.filter((c) => drawable(c.goals)).map((c) => ({x: c.goals[a], y: c.goals[b]})));
    // A log axis where every value is positive and they span a decade or more; within less, a
    // log axis has no tick to read and is nearly linear anyway.
    const logAxis = (values) =>
        values.every((v) => v > 0) && Math.max(...values) >= 10 * Math.min(...values);
    const logX = logAxis(all.map((p) => p.x)), logY = logAxis(all.map((p) => p.y));
    const canvas = el('canvas', {id: 'front-chart', 'data-points': points.length});
    frontBox.append(
        el('h3', {
          text: 'Pareto front: ' + front.points.length + ' tuned points' +
              (soft.length > 2 ? ' (first two of ' + soft.length + ' soft goals)' : '') +
              ', hypervolume ' + fmt(front.hypervolume, 4)
        }),
        el('p', {
          class: 'hint',
          text:
              'Click a point of the front (or its row\'s button below) to download its gains file, as ftctune pick --rule index:K writes it.'
        }),
        el('div', {class: 'chart-box tall'}, canvas));
    // A front without a feasible point: nothing to draw, and no point picked.
    if (!front.points.length || !front.picked) {
      frontBox.append(el('h3', {text: 'Pareto front: empty (no trial met the hard goals)'}));
      return;
    }
    const picked = front.points[front.picked.index];
    const datasets = [{label: 'front', data: points, backgroundColor: '#440154', pointRadius: 3}];
    if (picked && drawable(picked.goals))
      datasets.push({label: 'picked (' + front.picked.rule + ')', data: [{x: picked.goals[a], y: picked.goals[b]}],
                     pointRadius: 9, pointStyle: 'circle', backgroundColor: 'rgba(0,0,0,0)',
                     borderColor: '#21918c', borderWidth: 2});
    // Bands: v·(1 ± f/2) on each axis, kept above v/10 on a log axis (as the report does), a
    // gap between points (NaN breaks the line).
    const band = (v, f, log) => {
      if (!finite(f)) return [v, v];
      const half = 0.5 * f * Math.abs(v);
      return [log ? Math.max(v - half, 0.1 * v) : v - half, v + half];
    };
    const gap = {x: NaN, y: NaN};
    const bands = [];
    let banded = 0;
    for (const p of front.points) {
      if (!drawable(p.goals)) continue;
      const f = p.noise_floor || [];
      if (!finite(f[a]) && !finite(f[b])) continue;
      const x = p.goals[a], y = p.goals[b];
      const [x0, x1] = band(x, f[a], logX), [y0, y1] = band(y, f[b], logY);
      bands.push({x: x0, y}, {x: x1, y}, gap, {x, y: y0}, {x, y: y1}, gap);
      ++banded;
    }
    if (banded)
      datasets.push({label: 'noise floor (band of one relative spread)', data: bands, showLine: true,
                     spanGaps: false, pointRadius: 0, borderColor: '#8c8c8c', borderWidth: 1});
    // The pairs that are no trade-off, as front.json lists each point's partners.
    const partners = front.points.map((p) => p.within_noise || []);
    const links = [];
    front.points.forEach((p, i) => {
      for (const k of partners[i]) {
        const q = front.points[k];
        if (k > i && q && drawable(p.goals) && drawable(q.goals))
          links.push({x: p.goals[a], y: p.goals[b]}, {x: q.goals[a], y: q.goals[b]}, gap);
      }
    });
    if (links.length)
      datasets.push({label: "within one's noise floor on every goal: not a trade-off", data: links,
                     showLine: true, spanGaps: false, pointRadius: 0, borderColor: '#4d4d4d',
                     borderWidth: 1.5, borderDash: [5, 4]});
    canvas.dataset.noiseBands = String(banded);
    canvas.dataset.noiseLinks = String(links.length / 3);
    const styles = ['rect', 'triangle', 'rectRot', 'star', 'crossRot'];
    front.compared.forEach((c, i) => {
      if (drawable(c.goals))
        datasets.push({label: (c.role === 'baseline' ? "job's gains: " : '') + c.label + (c.feasible ? '' : ' (infeasible)'),
                       data: [{x: c.goals[a], y: c.goals[b]}], pointStyle: styles[i % styles.length],
                       pointRadius: 7, backgroundColor: colour(i + 1, 1, front.compared.length + 1)});
    });
    const chartReady = chartJs().then((Chart) => {
      if (!canvas.isConnected) return null;
      frontChart = new Chart(canvas, {
        type: 'scatter',
        data: {datasets},
        options: {
          animation: false,
          maintainAspectRatio: false,
          parsing: false,
          scales: {
            x: {
              type: logX ? 'logarithmic' : 'linear',
              grace: '5%',
              title: {display: true, text: axisTitle(name(front.goals[a]), logX)}
            },
            y: {
              type: logY ? 'logarithmic' : 'linear',
              grace: '5%',
              title: {display: true, text: axisTitle(name(front.goals[b]), logY)}
            }
          },
          plugins: {
            legend: {display: true, position: 'bottom'},
            tooltip: {
              callbacks: {
                label: (c) => c.datasetIndex === 0 ? 'point ' + c.raw.point + ': ' +
                        fmt(c.raw.x, 4) + ', ' + fmt(c.raw.y, 4) + ' (click: its gains)' :
                                                     c.dataset.label
              }
            }
          },
          // A click on a point of the front downloads that point's gains file.
          // (Every item under the pointer, not the nearest only: the picked ring, a band
          // or a compared controller may lie over the point.)
          onClick: (event, elements, chart) => {
            const hit = frontHits(chart, event)[0];
            if (hit) pickPoint(points[hit.index].point);
          },
          onHover: (event, elements, chart) => {
            canvas.style.cursor = frontHits(chart, event).length ? 'pointer' : 'default';
          }
        },
      });
      charts.push(frontChart);
      // The points of the front under the pointer, the nearest first.
      function frontHits(chart, event) {
        const d = (e) => Math.hypot(e.element.x - event.x, e.element.y - event.y);
        return chart.getElementsAtEventForMode(event, 'point', {intersect: true}, false)
            .filter((e) => e.datasetIndex === 0)
            .sort((p, q) => d(p) - d(q));
      }
      return frontChart;
    });
    chartReady.catch((e) => showError(message, e));
    // Every point: its soft goals with their floors (the spread, as the report prints it), and
    // the points it is no trade-off with.
    const softName = soft.map((i) => name(front.goals[i]));
    const percent = (f) => (finite(f) ? fmt(100 * f, 2) + ' %' : '–');
    frontBox.append(el(
        'div', {class: 'scroll'},
        el('table', {id: 'front-points'},
           el('thead', null,
              el('tr', null,
                 ['point', 'trial']
                     .concat(
                         ...softName.map((n) => [n, 'noise floor (spread)']),
                         ['feasible', 'no trade-off with', 'gains'])
                     .map((h) => el('th', {text: h})))),
           el('tbody', null,
              front.points.map(
                  (p, k) => el(
                      'tr', {class: k === front.picked.index ? 'picked' : ''},
                      el('td', {class: 'num', text: String(k)}),
                      el('td', {class: 'num', text: String(p.trial)}),
                      soft.map((i) => [el('td', {class: 'num', text: fmt(p.goals[i])}), el('td', {
                                         class: 'num',
                                         text: percent((p.noise_floor || [])[i])
                                       })]),
                      el('td', {text: p.feasible ? 'yes' : 'no'}),
                      el('td', {text: partners[k].map((i) => 'point ' + i).join(', ')}),
                      el('td', null, el('button', {
                           class: 'pick',
                           'data-point': k,
                           text: 'gains-point-' + k + '.json',
                           onclick: () => pickPoint(k)
                         }))))))));
    // The held-out check (issue 42): the front evaluated on members the run never saw (GET
    // .../held-out, what ftctune evaluate --front writes), each point's in-sample value joined
    // to its held-out one on the chart, and a table of both. The server keeps the latest.
    const count = el('input', {id: 'held-out-count', type: 'number', min: '1', step: '1', value: '1000'});
    const seed = el('input', {id: 'held-out-seed', type: 'number', min: '0', step: '1', value: '0'});
    const status = el('span', {id: 'held-out-status', class: 'hint'});
    const heldBox = el('div', {id: 'held-out'});
    const heldOutSection = el('div', {id: 'held-out-section', hidden: true});
    apiJson('/v1/jobs/' + id + '/job').then((stored) => {
      // Only a job with an ensemble has members it was not tuned on; evaluate's defaults: the
      // ensemble's count, its seed + 1.
      const e = stored.ensemble;
      if (!e) return;
      count.value = String(e.count);
      seed.value = String((e.seed || 0) + 1);
      heldOutSection.hidden = false;
    }).catch(() => {});
    const evaluateButton = el('button', {
      id: 'held-out-run',
      text: 'Evaluate the front on held-out members',
      onclick: async () => {
        evaluateButton.disabled = true;
        status.textContent = 'simulating every point on ' + count.value + ' held-out members…';
        try {
          showHeldOut(await apiJson('/v1/jobs/' + id + '/held-out?count=' +
                                    encodeURIComponent(count.value) + '&seed=' +
                                    encodeURIComponent(seed.value)));
          status.textContent = '';
        } catch (e) {
          status.textContent = '';
          showError(message, e);
        } finally {
          evaluateButton.disabled = false;
        }
      }
    });
    frontBox.append(heldOutSection);
    heldOutSection.append(
        el('h3', {text: 'Held-out check'}),
        el('p', {
          class: 'hint',
          text: 'A front is tuned on its ensemble\'s members; before picking a point, see how each ' +
              'point does on members the run never saw (another seed). In-sample values are ' +
              'the run\'s, held-out ones come from the same simulations as ftctune evaluate --front.'
        }),
        el('div', {class: 'toolbar'}, 'members ', count, ' seed ', seed, ' ', evaluateButton, ' ', status),
        heldBox);
    heldOutView = showHeldOut;
    function showHeldOut(held) {
      clear(heldBox);
      const on = held.points.filter((p) => !p.dominated).length;
      const knee = held.picked ? held.picked.index : null;
      heldBox.append(el('p', {
        id: 'held-out-summary',
        text: 'On ' + held.held_out.count + ' held-out members (seed ' + held.held_out.seed + '): ' +
            on + ' of ' + held.points.length + ' points stay on the front; hypervolume ' +
            fmt(held.hypervolume, 4) + ' (in sample ' + fmt(held.held_out.in_sample_hypervolume, 4) +
            ', the run\'s reference point)' +
            (knee === null ? '; no point meets the hard goals held out.' :
                             '; the held-out knee is point ' + knee + '.')
      }));
      const ratio = (h, i) => (finite(h) && finite(i) && i !== 0 ? fmt(h / i, 3) + '×' : '–');
      heldBox.append(el(
          'div', {class: 'scroll'},
          el('table', {id: 'held-out-points'},
             el('thead', null,
                el('tr', null,
                   ['point']
                       .concat(...softName.map((n) => [n + ' in sample', 'held out', 'held out / in sample']),
                               ['feasible held out', 'on the held-out front'])
                       .map((h) => el('th', {text: h})))),
             el('tbody', null,
                held.points.map((p, k) => el(
                    'tr', {class: k === knee ? 'picked' : ''},
                    el('td', {class: 'num', text: String(k)}),
                    soft.map((i) => [el('td', {class: 'num', text: fmt(p.in_sample[i])}),
                                     el('td', {class: 'num', text: fmt(p.goals[i])}),
                                     el('td', {class: 'num', text: ratio(p.goals[i], p.in_sample[i])})]),
                    el('td', {text: p.feasible ? 'yes' : 'no'}),
                    el('td', {text: p.dominated ? 'no' : 'yes'})))))));
      chartReady.then((chart) => {
        if (!chart) return;
        chart.data.datasets = chart.data.datasets.filter((d) => !d.heldOut);
        const shown = held.points.filter((p) => drawable(p.goals));
        const joins = [];
        for (const p of held.points)
          if (drawable(p.goals) && drawable(p.in_sample))
            joins.push({x: p.in_sample[a], y: p.in_sample[b]}, {x: p.goals[a], y: p.goals[b]}, gap);
        chart.data.datasets.push(
            {label: 'held out (' + held.held_out.count + ' members)', heldOut: true,
             data: shown.map((p) => ({x: p.goals[a], y: p.goals[b]})), pointRadius: 4,
             pointStyle: 'triangle', backgroundColor: '#fd9a44'},
            {label: 'in sample → held out', heldOut: true, data: joins, showLine: true,
             spanGaps: false, pointRadius: 0, borderColor: '#fd9a44', borderWidth: 1});
        // Log axes stay log only while every value, held out too, allows one.
        const xs = all.map((q) => q.x).concat(shown.map((p) => p.goals[a]));
        const ys = all.map((q) => q.y).concat(shown.map((p) => p.goals[b]));
        if (chart.options.scales.x.type === 'logarithmic' && !xs.every((v) => v > 0))
          chart.options.scales.x.type = 'linear';
        if (chart.options.scales.y.type === 'logarithmic' && !ys.every((v) => v > 0))
          chart.options.scales.y.type = 'linear';
        // The goals' labels name the run's aggregate (its members); the triangles are the same
        // measure over the held-out members, which the axis titles say too.
        const title = (g, axis) => axisTitle(name(g), axis.type === 'logarithmic') +
            '; triangles: over ' + held.held_out.count + ' held-out members';
        chart.options.scales.x.title.text = title(front.goals[a], chart.options.scales.x);
        chart.options.scales.y.title.text = title(front.goals[b], chart.options.scales.y);
        chart.update('none');
        canvas.dataset.heldOut = String(shown.length);
      }).catch((e) => showError(message, e));
    }
  }
  // The held-out view of the front drawn last (renderFront sets it), for a kept held-out.json.
  let heldOutView = null;
  // Point k's gains file (GET .../gains?pick=index:K, the library's pick), downloaded.
  function pickPoint(k) {
    const name = 'gains-point-' + k + '.json';
    frontBox.dataset.picked = String(k);
    download('/v1/jobs/' + id + '/gains?pick=index:' + k, name).catch((e) => showError(message, e));
  }

  // The page opens a job and its live stream reopens it, so two loads can overlap: the newer one
  // wins, and an older one still awaiting its answers draws nothing (it drew every download
  // button twice).
  let resultsRun = 0;
  const loadResults = () => loadingWhile(drawResults);
  async function drawResults() {
    const run = ++resultsRun;
    const stale = () => run !== resultsRun;
    const finished = isFinished(job.status);
    let c = null, gains = null, recorded = [];
    try {
      if (finished) c = await apiJson('/v1/jobs/' + id + '/comparison');
      if (finished) gains = await apiJson('/v1/jobs/' + id + '/gains');
      if (c) recorded = await metrics();
    } catch (e) {
      if (!(e instanceof ApiError && e.status === 409)) showError(message, e);
    }
    if (stale()) return;
    clear(figures);
    clear(frontBox);
    clear(downloads);
    renderComparison(c, gains, recorded);
    const warned = (gains && gains.warnings && gains.warnings.length) || 0;
    if (warned !== warnings) {
      warnings = warned;
      renderHeader();
    }
    const items = [['gains.json', '/gains'], ['trials.csv', '/trials'], ['history.csv', '/history']];
    if (c) items.push(['comparison.md', '/comparison?format=md'], ['report.html', '/report']);
    if (job.progress.iteration !== null && (c || job.status === 'running'))
      for (const [name, path] of items)
        downloads.appendChild(el('button', {text: name, 'data-file': name, onclick: () =>
          download('/v1/jobs/' + id + path, name).catch((e) => showError(message, e))}));
    else downloads.appendChild(el('span', {text: 'No results (yet).'}));
    // The landscape and evaluation figures, if the job has them.
    if (!c) return;
    try {
      const list = await apiJson('/v1/jobs/' + id + '/files');
      if (stale()) return;
      // A front's files, to pick another point offline (ftctune pick) or plot it.
      for (const name of ['front.json', 'front.csv'])
        if (list.files.some((f) => f.name === name))
          downloads.appendChild(el('button', {text: name, 'data-file': name, onclick: () =>
            download('/v1/jobs/' + id + '/files/' + name, name).catch((e) => showError(message, e))}));
      if (list.files.some((f) => f.name === 'front.json')) {
        const front = await apiJson('/v1/jobs/' + id + '/files/front.json');
        if (stale()) return;
        renderFront(front);
        // A held-out check asked for before (the server keeps the latest).
        if (list.files.some((f) => f.name === 'held-out.json')) {
          const held = await apiJson('/v1/jobs/' + id + '/files/held-out.json');
          if (stale()) return;
          if (heldOutView) heldOutView(held);
        }
      }
      const images = list.files.filter((f) => /\.(png|svg)$/.test(f.name));
      if (images.length) figures.appendChild(el('h3', {text: 'Figures'}));
      for (const f of images) {
        // Each path segment encoded: a stored name is data, never a path of the API.
        const res = await request('/v1/jobs/' + id + '/files/' +
                                  f.name.split('/').map(encodeURIComponent).join('/'));
        if (!res.ok) continue;
        const blob = await res.blob();
        if (stale()) return;
        const url = URL.createObjectURL(blob);
        figures.appendChild(el('figure', null, el('img', {src: url, alt: f.name}),
                               el('figcaption', {text: f.name})));
      }
    } catch (e) { /* no files: nothing to show */ }
  }

  // Loads under way, the job's and its results' (body's data-loading, which the browser test
  // waits on before it reads the page).
  let loading = 0;
  async function loadingWhile(work) {
    document.body.dataset.loading = String(++loading);
    try {
      return await work();
    } finally {
      document.body.dataset.loading = String(--loading);
    }
  }
  const loadJob = () => loadingWhile(readJob);
  async function readJob() {
    try {
      const fresh = await apiJson('/v1/jobs/' + id);
      // An event may have told of the job's end while this answer was on its way: an older
      // snapshot does not take the finished job back to running (its results would vanish).
      if (!(job && isFinished(job.status) && !isFinished(fresh.status))) job = fresh;
    } catch (e) {
      clear(header);
      showError(header, e);
      return;
    }
    renderHeader();
    await loadProgress();
    await loadResults();
  }
  const refresh = throttle(loadProgress, 700);
  let lastStatus = null;
  const off = live.on((ev) => {
    if (ev.type === 'open') return loadJob();
    if (ev.type === 'deleted' && ev.data.id === id) { location.hash = '#/'; return; }
    if (ev.type !== 'job' || ev.data.id !== id) return;
    job = ev.data;
    renderHeader();
    refresh();
    if (job.status !== lastStatus && isFinished(job.status)) loadResults();
    lastStatus = job.status;
  });
  loadJob().then(() => { lastStatus = job && job.status; });
  loadScales();
  let gone = false;
  chartJs().then((Chart) => { if (!gone) makeCharts(Chart); }).catch((e) => showError(message, e));
  const tick = setInterval(() => { if (job && job.status === 'running') renderHeader(); }, 1000);
  return () => { gone = true; off(); clearInterval(tick); charts.forEach((c) => c.destroy()); };
}

function submitView(main) {
  const text = el('textarea', {id: 'job-text', spellcheck: 'false',
                               placeholder: 'Paste a job file (ftctune.job/1) here, or drop one below.'});
  const file = el('input', {type: 'file', id: 'job-file', accept: '.json,application/json'});
  const drop = el('div', {class: 'drop', id: 'drop'}, 'Drop a job file here, or choose one: ', file);
  const result = el('div', {id: 'validation'});
  const submit = el('button', {id: 'submit-job', text: 'Submit', disabled: true});
  main.append(el('h1', {text: 'Submit a job'}), drop, text,
              el('div', {class: 'toolbar'}, submit), result);

  let seq = 0;
  async function check() {
    const mine = ++seq;
    clear(result);
    submit.disabled = true;
    if (!text.value.trim()) return;
    try {
      const v = await apiJson('/v1/validate', {method: 'POST', body: text.value,
                                               headers: {'Content-Type': 'application/json'}});
      if (mine !== seq) return;
      result.appendChild(el('div', {class: 'ok', id: 'valid', text: 'Valid: job ' + v.name + ', tuning ' +
        v.parameters.join(', ') + ' in ' + v.total_evaluations + ' evaluations (' + v.iterations + ' iterations).'}));
      submit.disabled = false;
    } catch (e) {
      if (mine !== seq) return;
      showError(result, e);
    }
  }
  let typing = null;
  const later = () => { clearTimeout(typing); typing = setTimeout(check, 300); };
  text.addEventListener('input', later);
  const load = (f) => f.text().then((t) => { text.value = t; check(); });
  file.addEventListener('change', () => { if (file.files.length) load(file.files[0]); });
  drop.addEventListener('dragover', (ev) => { ev.preventDefault(); drop.classList.add('over'); });
  drop.addEventListener('dragleave', () => drop.classList.remove('over'));
  drop.addEventListener('drop', (ev) => {
    ev.preventDefault();
    drop.classList.remove('over');
    if (ev.dataTransfer.files.length) load(ev.dataTransfer.files[0]);
  });
  submit.addEventListener('click', async () => {
    submit.disabled = true;
    try {
      const created = await apiJson('/v1/jobs', {method: 'POST', body: text.value,
                                                 headers: {'Content-Type': 'application/json'}});
      location.hash = '#/job/' + created.id;
    } catch (e) {
      clear(result);
      showError(result, e);
      submit.disabled = false;
    }
  });
  return () => clearTimeout(typing);
}

window.addEventListener('hashchange', route);
// A browser gives a server six connections at most: a hidden or left page gives its stream back
// (and reads what changed meanwhile when it is shown again).
document.addEventListener('visibilitychange', () => (document.hidden ? live.stop() : live.start()));
window.addEventListener('pagehide', () => live.stop());
window.addEventListener('pageshow', (ev) => { if (ev.persisted) live.start(); });
live.start();
route();
