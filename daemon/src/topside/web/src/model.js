// The page's state, fed by navtool topside's /ws frames {channel, msg}. No DOM here.
export const STALE_AFTER_S = 2.0;   // a sensor, the solution or the feed older than this is stale
const MAX_TRACK = 20000;
const MAX_SERIES = 3000;

export function createModel() {
  return {
    solution: null, solutionReceivedMs: 0,
    health: null, healthReceivedMs: 0,
    track: [],                 // [x north, y east]
    states: new Map(),         // state_id -> delayed_state_bound_t JSON
    links: new Map(),          // "i-j" -> camera_link_t JSON
    proposals: new Map(),      // sequence -> link_proposal_t JSON
    sigmaSeries: [[], []],     // t s, sigma_xy m
    nisSeries: new Map(),      // sensor -> [[t], [nis_mean]]
    activity: new Map(),       // sensor -> {count, changedMs}: when its counters last moved
    configSensors: [],         // [{name, type}] from navtool topside --config
  };
}

/// Applies one feed frame; returns true when something to draw changed.
export function applyFrame(model, frame, nowMs) {
  const m = frame.msg;
  switch (frame.channel) {
    case 'NAVD_SOLUTION': {
      model.solution = m;
      model.solutionReceivedMs = nowMs;
      const last = model.track[model.track.length - 1];
      if (!last || last[0] !== m.p_world_m[0] || last[1] !== m.p_world_m[1]) {
        model.track.push([m.p_world_m[0], m.p_world_m[1]]);
        if (model.track.length > MAX_TRACK) model.track.splice(0, model.track.length - MAX_TRACK);
      }
      pushSeries(model.sigmaSeries, m.utime / 1e6, m.sigma_xy_m);
      return true;
    }
    case 'NAVD_HEALTH':
      model.health = m;
      model.healthReceivedMs = nowMs;
      for (const s of m.sensors) {
        noteActivity(model, s, nowMs);
        if (!model.nisSeries.has(s.name)) model.nisSeries.set(s.name, [[], []]);
        pushSeries(model.nisSeries.get(s.name), m.utime / 1e6, s.nis_mean >= 0 ? s.nis_mean : null);
      }
      return true;
    case 'NAVD_BOUNDS':
      model.states.set(m.state_id, m);
      return true;
    case 'NAVD_CAMERA_LINKS':
      model.links.set(`${m.state_id_i}-${m.state_id_j}`, m);
      return true;
    case 'TOPSIDE_CONFIG':
      model.configSensors = m.sensors;
      return true;
    case 'NAV_LINK_PROPOSAL':
      model.proposals.set(m.sequence, m);
      return true;
    default:
      return false;
  }
}

function pushSeries(series, t, v) {
  series[0].push(t);
  series[1].push(v);
  if (series[0].length > MAX_SERIES) { series[0].shift(); series[1].shift(); }
}

/// Temporal link: no known delayed state between its two states (consecutive images).
export function isTemporal(model, link) {
  const lo = Math.min(link.state_id_i, link.state_id_j), hi = Math.max(link.state_id_i, link.state_id_j);
  for (const id of model.states.keys()) if (id > lo && id < hi) return false;
  return true;
}

/// Proposals not yet answered by a camera link, as pairs of known states (matched by image time).
export function pendingProposals(model) {
  const byImageTime = new Map();
  for (const s of model.states.values()) byImageTime.set(s.image_time_us, s);
  const out = [];
  for (const p of model.proposals.values()) {
    const si = byImageTime.get(p.time_of_validity_i_us), sj = byImageTime.get(p.time_of_validity_j_us);
    if (si && sj && (model.links.has(`${si.state_id}-${sj.state_id}`) ||
                     model.links.has(`${sj.state_id}-${si.state_id}`))) continue;
    out.push({ proposal: p, si, sj });
  }
  return out;
}

// A sensor's activity: records decoded plus updates fused or refused. navd reports
// last_message_age_s only for device sensors (-1 in replay), so the page also times when these
// counters last moved, which covers replayed and device sensors alike.
function noteActivity(model, s, nowMs) {
  const count = s.records + s.updates + s.rejected_updates;
  const prev = model.activity.get(s.name);
  if (!prev) {
    const age = s.last_message_age_s >= 0 ? s.last_message_age_s * 1000 : 0;
    model.activity.set(s.name, { count, changedMs: count > 0 ? nowMs - age : -Infinity });
  } else if (count !== prev.count) {
    model.activity.set(s.name, { count, changedMs: nowMs });
  }
}

/// A sensor's last-message age now (s): the younger of navd's reported age (extrapolated from
/// the health message) and the time since the sensor's counters last moved; Infinity if never.
export function sensorAgeS(model, sensor, nowMs) {
  const act = model.activity.get(sensor.name);
  const byCounters = act ? (nowMs - act.changedMs) / 1000 : Infinity;
  if (sensor.last_message_age_s < 0) return byCounters;
  return Math.min(byCounters, sensor.last_message_age_s + (nowMs - model.healthReceivedMs) / 1000);
}

/// The newest sensor activity seen (ms, page clock), -Infinity if none.
export function lastActivityMs(model) {
  let t = -Infinity;
  for (const a of model.activity.values()) t = Math.max(t, a.changedMs);
  return t;
}

/// 'ok' | 'stale' | 'faulty' for one sensor row.
export function sensorState(model, sensor, nowMs) {
  if (!sensor.connected && sensor.records > 0) return 'faulty';  // a device that vanished
  if (sensorAgeS(model, sensor, nowMs) > STALE_AFTER_S) return 'stale';
  if (sensor.nis_mean >= 0 && sensor.nis_expected > 0 && sensor.nis_mean > 3 * sensor.nis_expected) return 'faulty';
  return 'ok';
}
