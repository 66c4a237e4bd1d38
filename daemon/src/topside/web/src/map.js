// Top view in metres, north up (x north -> screen up, y east -> screen right), equal scale.
import { isTemporal, pendingProposals } from './model.js';

const COLORS = { track: '#5fb3ff', state: 'rgba(138,167,255,0.9)', temporal: '#3ccf6e',
                 loop: '#ff9a1f', pending: '#c8c8c8', vehicle: '#ffe14f', grid: '#1f2a35' };

/// Draws the model; returns what it drew {states, links, temporal, loop, pending}.
export function drawMap(canvas, model, nowMs, staleAfterS) {
  const dpr = window.devicePixelRatio || 1;
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
    canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
  }
  const ctx = canvas.getContext('2d');
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.clearRect(0, 0, w, h);

  const pts = model.track.slice();
  for (const s of model.states.values()) pts.push([s.mean_pose[0], s.mean_pose[1]]);
  if (pts.length === 0) return { states: 0, links: 0, temporal: 0, loop: 0, pending: 0 };
  let nMin = Infinity, nMax = -Infinity, eMin = Infinity, eMax = -Infinity;
  for (const [n, e] of pts) { nMin = Math.min(nMin, n); nMax = Math.max(nMax, n); eMin = Math.min(eMin, e); eMax = Math.max(eMax, e); }
  const margin = 40;
  const span = Math.max(nMax - nMin, eMax - eMin, 2);
  const scale = Math.min(w - 2 * margin, h - 2 * margin) / span;  // px per m
  const nMid = (nMin + nMax) / 2, eMid = (eMin + eMax) / 2;
  const toScreen = (n, e) => [w / 2 + (e - eMid) * scale, h / 2 - (n - nMid) * scale];

  drawGrid(ctx, w, h, scale, toScreen, nMid, eMid);

  // Track.
  ctx.strokeStyle = COLORS.track; ctx.lineWidth = 1.5; ctx.beginPath();
  model.track.forEach(([n, e], i) => { const [x, y] = toScreen(n, e); if (i) ctx.lineTo(x, y); else ctx.moveTo(x, y); });
  ctx.stroke();

  // Links: accepted ones, temporal vs loop-closing; pending proposals dashed.
  let temporal = 0, loop = 0;
  for (const l of model.links.values()) {
    const a = model.states.get(l.state_id_i), b = model.states.get(l.state_id_j);
    if (!l.accepted || !a || !b) continue;
    const t = isTemporal(model, l);
    t ? ++temporal : ++loop;
    line(ctx, toScreen(a.mean_pose[0], a.mean_pose[1]), toScreen(b.mean_pose[0], b.mean_pose[1]),
         t ? COLORS.temporal : COLORS.loop, 2, []);
  }
  const pending = pendingProposals(model);
  for (const { si, sj } of pending) {
    if (si && sj) line(ctx, toScreen(si.mean_pose[0], si.mean_pose[1]), toScreen(sj.mean_pose[0], sj.mean_pose[1]), COLORS.pending, 1, [4, 4]);
  }

  // Delayed states with their 3-sigma bound ellipses.
  for (const s of model.states.values()) {
    const [x, y] = toScreen(s.mean_pose[0], s.mean_pose[1]);
    const el = s.ellipse_3sigma;
    ctx.strokeStyle = COLORS.state; ctx.lineWidth = 1;
    ctx.beginPath();
    ctx.ellipse(x, y, Math.max(el.semi_major_m * scale, 0.5), Math.max(el.semi_minor_m * scale, 0.5), el.angle_rad - Math.PI / 2, 0, 2 * Math.PI);
    ctx.stroke();
    ctx.fillStyle = COLORS.state; ctx.fillRect(x - 1.5, y - 1.5, 3, 3);
  }

  // Vehicle: heading triangle and 1-sigma ellipse; faded when the solution is stale.
  const sol = model.solution;
  if (sol) {
    const stale = (nowMs - model.solutionReceivedMs) / 1000 > staleAfterS;
    ctx.globalAlpha = stale ? 0.35 : 1.0;
    const [x, y] = toScreen(sol.p_world_m[0], sol.p_world_m[1]);
    const el = sol.ellipse_1sigma;
    ctx.strokeStyle = accuracyColor(sol.sigma_xy_m); ctx.lineWidth = 1.5;
    ctx.beginPath();
    ctx.ellipse(x, y, Math.max(el.semi_major_m * scale, 0.5), Math.max(el.semi_minor_m * scale, 0.5), el.angle_rad - Math.PI / 2, 0, 2 * Math.PI);
    ctx.stroke();
    const psi = sol.heading_rad, r = 12;
    const dir = [Math.sin(psi), -Math.cos(psi)], side = [Math.cos(psi), Math.sin(psi)];
    ctx.fillStyle = stale ? '#888' : accuracyColor(sol.sigma_xy_m);
    ctx.beginPath();
    ctx.moveTo(x + dir[0] * r, y + dir[1] * r);
    ctx.lineTo(x - dir[0] * r * 0.6 + side[0] * r * 0.5, y - dir[1] * r * 0.6 + side[1] * r * 0.5);
    ctx.lineTo(x - dir[0] * r * 0.6 - side[0] * r * 0.5, y - dir[1] * r * 0.6 - side[1] * r * 0.5);
    ctx.closePath(); ctx.fill();
    ctx.globalAlpha = 1.0;
  }
  return { states: model.states.size, links: temporal + loop, temporal, loop, pending: pending.length };
}

/// Position accuracy as colour: green below 1 m (1 sigma), yellow below 5 m, red beyond.
export function accuracyColor(sigmaM) {
  return sigmaM < 1 ? '#3ccf6e' : sigmaM < 5 ? '#ffe14f' : '#ff5a4f';
}

function line(ctx, [x0, y0], [x1, y1], color, width, dash) {
  ctx.strokeStyle = color; ctx.lineWidth = width; ctx.setLineDash(dash);
  ctx.beginPath(); ctx.moveTo(x0, y0); ctx.lineTo(x1, y1); ctx.stroke(); ctx.setLineDash([]);
}

function drawGrid(ctx, w, h, scale, toScreen, nMid, eMid) {
  const raw = 80 / scale, mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map((k) => k * mag).find((s) => s >= raw);
  ctx.strokeStyle = COLORS.grid; ctx.fillStyle = '#6b7b8a'; ctx.lineWidth = 1; ctx.font = '10px sans-serif';
  const halfN = h / 2 / scale, halfE = w / 2 / scale;
  for (let n = Math.ceil((nMid - halfN) / step) * step; n <= nMid + halfN; n += step) {
    const [, y] = toScreen(n, eMid); ctx.beginPath(); ctx.moveTo(0, y); ctx.lineTo(w, y); ctx.stroke();
    ctx.fillText(`${+n.toFixed(3)} m N`, 2, y - 2);
  }
  for (let e = Math.ceil((eMid - halfE) / step) * step; e <= eMid + halfE; e += step) {
    const [x] = toScreen(nMid, e); ctx.beginPath(); ctx.moveTo(x, 0); ctx.lineTo(x, h); ctx.stroke();
    ctx.fillText(`${+e.toFixed(3)} m E`, x + 2, h - 4);
  }
  ctx.fillStyle = '#dde4ea'; ctx.font = 'bold 14px sans-serif'; ctx.fillText('N ↑', w - 36, 18);
}
