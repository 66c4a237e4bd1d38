// navd topside page: connects to /ws, keeps the model (model.js), draws the map (map.js), the
// vehicle and health panels and two uPlot time series. window.topside exposes the model.
import uPlot from 'uplot';
import { createModel, applyFrame, sensorAgeS, sensorState, lastActivityMs, STALE_AFTER_S } from './model.js';
import { drawMap, accuracyColor } from './map.js';

const model = createModel();
const $ = (id) => document.getElementById(id);
let dirty = true;
let feedUp = false;
window.topside = { model, drawn: null, lastActivityMs: () => lastActivityMs(model) };

function connect() {
  const ws = new WebSocket(`ws://${location.host}/ws`);
  ws.onopen = () => { feedUp = true; dirty = true; };
  ws.onmessage = (ev) => { if (applyFrame(model, JSON.parse(ev.data), Date.now())) dirty = true; };
  ws.onclose = () => { feedUp = false; dirty = true; setTimeout(connect, 1000); };
}

const FILTER_STATUS = ['ok', 'degraded', 'initialising'];
const fixed = (v, d) => (v === undefined || v === null || !isFinite(v) ? '–' : v.toFixed(d));

function renderVehicle(now) {
  const s = model.solution;
  if (!s) return;
  $('depth').textContent = fixed(s.depth_m, 2);
  $('heading').textContent = fixed(((s.heading_rad * 180 / Math.PI) % 360 + 360) % 360, 1);
  $('speed').textContent = fixed(s.speed_mps, 2);
  $('sigma').textContent = fixed(s.sigma_xy_m, 2);
  $('sigma').style.color = accuracyColor(s.sigma_xy_m);
  const age = (now - model.solutionReceivedMs) / 1000;
  $('solution-age').textContent = fixed(age, 1);
  $('solution-age').className = age > STALE_AFTER_S ? 'stale' : 'ok';
  const fs = $('filter-status');
  fs.textContent = FILTER_STATUS[s.filter_status] ?? `status ${s.filter_status}`;
  fs.className = s.filter_status === 0 ? 'ok' : s.filter_status === 1 ? 'faulty' : 'stale';
}

function renderHealth(now) {
  const h = model.health;
  if (!h) return;
  const body = $('health-table').tBodies[0];
  const rows = h.sensors.map((s) => {
    const state = sensorState(model, s, now);
    const age = sensorAgeS(model, s, now);
    return `<tr data-sensor="${escape(s.name)}" class="${state}"><td>${escape(s.name)}</td>` +
      `<td>${s.connected ? 'yes' : s.records > 0 ? 'NO' : 'log'}</td><td>${fixed(s.rate_hz, 1)}</td>` +
      `<td>${isFinite(age) ? fixed(age, 1) : 'never'}</td>` +
      `<td class="${s.decode_errors > 0 ? 'faulty' : ''}">${s.decode_errors}</td>` +
      `<td>${s.nis_mean >= 0 ? fixed(s.nis_mean, 2) : '–'} / ${fixed(s.nis_expected, 1)}</td>` +
      `<td>${s.updates} / ${s.rejected_updates}</td></tr>`;
  });
  for (const c of model.configSensors) {  // configured, but absent from navd's health
    if (h.sensors.some((s) => s.name === c.name)) continue;
    rows.push(`<tr data-sensor="${escape(c.name)}" class="stale"><td>${escape(c.name)}</td>` +
              `<td colspan="6">${escape(c.type)}: not reported in navd's health</td></tr>`);
  }
  body.innerHTML = rows.join('');
  const dvl = h.sensors.find((s) => /dvl/i.test(s.name));
  const lock = dvl && sensorState(model, dvl, now) === 'ok' &&
               (dvl.last.length === 0 || dvl.last.some((a) => a.fused));
  $('dvl-lock').textContent = dvl ? (lock ? 'locked' : 'LOST') : 'no DVL';
  $('dvl-lock').className = lock ? 'ok' : 'faulty';
  $('cg').textContent = h.cg_relative_residual.toExponential(1) + ` (${h.cg_iterations} it)`;
  $('queue').textContent = `${h.queue_depth} / ${h.queue_capacity}`;
  $('cpu').textContent = fixed(h.cpu_percent, 0) + ' %';
  $('rss').textContent = fixed(h.rss_mb, 0) + ' MiB';
  $('navd-status').textContent = h.status;
}

function escape(text) {
  return String(text).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' })[c]);
}

// Time series: position sigma, and NIS mean per sensor (rebuilt when the sensor set changes).
const plotSize = () => ({ width: Math.max(300, (window.innerWidth - 40) / 2), height: 160 });
const sigmaPlot = new uPlot({ ...plotSize(), title: 'position 1σ (m)',
  series: [{}, { label: 'σ xy', stroke: '#ffe14f' }], axes: [{ stroke: '#aab' }, { stroke: '#aab' }] },
  model.sigmaSeries, $('plot-sigma'));
let nisPlot = null, nisNames = '';
const NIS_COLORS = ['#5fb3ff', '#3ccf6e', '#ff9a1f', '#ff5a4f', '#c58cff', '#f0f0f0'];

function renderPlots() {
  sigmaPlot.setData(model.sigmaSeries);
  const names = [...model.nisSeries.keys()];
  if (names.length === 0) return;
  const t = model.nisSeries.get(names[0])[0];
  const data = [t, ...names.map((n) => model.nisSeries.get(n)[1].slice(-t.length))];
  if (names.join() !== nisNames) {
    nisPlot?.destroy();
    nisNames = names.join();
    nisPlot = new uPlot({ ...plotSize(), title: 'NIS mean per sensor (expected: dim z)',
      series: [{}, ...names.map((n, i) => ({ label: n, stroke: NIS_COLORS[i % NIS_COLORS.length] }))],
      axes: [{ stroke: '#aab' }, { stroke: '#aab' }] }, data, $('plot-nis'));
  } else {
    nisPlot.setData(data);
  }
}

let lastPanels = 0;
function frame() {
  const now = Date.now();
  const link = $('link-status');
  link.textContent = feedUp ? 'live' : 'disconnected';
  link.className = feedUp ? 'ok' : 'faulty';
  if (dirty || now - lastPanels > 250) {  // ages and staleness move with the clock
    const drawn = drawMap($('map'), model, now, STALE_AFTER_S);
    window.topside.drawn = drawn;
    $('n-states').textContent = drawn.states;
    $('n-links').textContent = drawn.links;
    $('n-temporal').textContent = drawn.temporal;
    $('n-loop').textContent = drawn.loop;
    $('n-pending').textContent = drawn.pending;
    renderVehicle(now);
    renderHealth(now);
    if (dirty) renderPlots();
    dirty = false;
    lastPanels = now;
  }
  requestAnimationFrame(frame);
}

connect();
requestAnimationFrame(frame);
