// Foxglove ws-protocol client test (run by daemon/tests/topside_foxglove_test.cpp):
//   node --experimental-websocket foxglove_client.mjs WS_URL EXPECTED_JSON
// Subscribes with @foxglove/ws-protocol's FoxgloveClient to /navd/pose (foxglove.PoseInFrame)
// and /navd/bounds (foxglove.SceneUpdate) and checks the decoded messages against what the
// driver published on LCM (EXPECTED_JSON: the solution's position and roll/pitch/heading, the
// bound states' ids, means and diagonal position covariances). Exit 0 on success.
import wsProtocol from '@foxglove/ws-protocol';
import fs from 'node:fs';

const { FoxgloveClient } = wsProtocol;
const [url, expectedPath] = process.argv.slice(2);
const expected = JSON.parse(fs.readFileSync(expectedPath, 'utf8'));
const fail = (why) => { console.error(`foxglove_client: FAIL: ${why}`); process.exit(1); };
const near = (a, b, tol, what) => { if (!(Math.abs(a - b) <= tol)) fail(`${what}: ${a} != ${b}`); };
setTimeout(() => fail('no pose and bounds within 20 s'), 20000).unref();

// Independent reference: q = qz(h) qy(p) qx(r) by quaternion products.
const mul = (a, b) => ({
  w: a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, x: a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
  y: a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, z: a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w });
const axis = (ax, ang) => ({ w: Math.cos(ang / 2), x: 0, y: 0, z: 0, [ax]: Math.sin(ang / 2) });

const client = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
const topicBySub = new Map();
const seen = { pose: false, bounds: false };
let serverInfo = null;
client.on('serverInfo', (info) => { serverInfo = info; });
client.on('error', (e) => fail(`client error: ${e.message}`));
client.on('advertise', (channels) => {
  if (!serverInfo) fail('advertise before serverInfo');
  for (const topic of ['/navd/pose', '/navd/bounds']) {
    const ch = channels.find((c) => c.topic === topic);
    if (!ch) fail(`${topic} not advertised`);
    if (ch.encoding !== 'json') fail(`${topic} encoding ${ch.encoding}`);
    topicBySub.set(client.subscribe(ch.id), { topic, schemaName: ch.schemaName });
  }
});
client.on('message', ({ subscriptionId, timestamp, data }) => {
  const sub = topicBySub.get(subscriptionId);
  if (!sub) fail(`message for unknown subscription ${subscriptionId}`);
  if (typeof timestamp !== 'bigint' || timestamp <= 0n) fail(`bad log time ${timestamp}`);
  const msg = JSON.parse(new TextDecoder().decode(data));
  if (sub.topic === '/navd/pose') {
    if (sub.schemaName !== 'foxglove.PoseInFrame') fail(`pose schema ${sub.schemaName}`);
    const p = msg.pose.position, q = msg.pose.orientation, [r, pi, h] = expected.rph_rad;
    expected.p_world_m.forEach((v, i) => near([p.x, p.y, p.z][i], v, 1e-9, `position[${i}]`));
    const ref = mul(mul(axis('z', h), axis('y', pi)), axis('x', r));
    for (const k of ['x', 'y', 'z', 'w']) near(q[k], ref[k], 1e-9, `orientation.${k}`);
    if (msg.frame_id !== 'ned') fail(`frame_id ${msg.frame_id}`);
    seen.pose = true;
  } else {
    if (sub.schemaName !== 'foxglove.SceneUpdate') fail(`bounds schema ${sub.schemaName}`);
    const ids = msg.entities.map((e) => e.id).sort();
    const want = expected.states.map((s) => `state/${s.state_id}`).sort();
    if (JSON.stringify(ids) !== JSON.stringify(want)) fail(`entities ${ids} != ${want}`);
    for (const s of expected.states) {
      const e = msg.entities.find((x) => x.id === `state/${s.state_id}`);
      const sphere = e.spheres[0];
      s.mean_m.forEach((v, i) => near([sphere.pose.position.x, sphere.pose.position.y, sphere.pose.position.z][i], v, 1e-9, `state ${s.state_id} mean[${i}]`));
      // Diagonal covariance: the 3-sigma ellipsoid's full axes are 6 sqrt(var), in some order.
      const size = [sphere.size.x, sphere.size.y, sphere.size.z].sort((a, b) => a - b);
      const want3 = s.variances_m2.map((v) => 6 * Math.sqrt(v)).sort((a, b) => a - b);
      want3.forEach((v, i) => near(size[i], v, 1e-9, `state ${s.state_id} size`));
    }
    seen.bounds = true;
  }
  if (seen.pose && seen.bounds) {
    console.log('foxglove_client: pose and bounds match what was published');
    process.exit(0);
  }
});
