// Real-browser test of the topside page (run by daemon/tests/topside_browser_test.cpp):
//   node browser.mjs PAGE_URL WORK_DIR
// Opens the page in Debian's chromium through playwright-core, writes WORK_DIR/page-ready once
// the feed is live, waits for WORK_DIR/control.json (written by the driver when navd's replay
// has ended), reads what the page shows, saves WORK_DIR/topside.png, then measures how long
// after the last health message every sensor row turns stale. Writes WORK_DIR/result.json.
import { chromium } from 'playwright-core';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const [url, dir] = process.argv.slice(2);
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'topside-chromium-'));
const context = await chromium.launchPersistentContext(userDataDir, {
  executablePath: '/usr/bin/chromium',
  headless: true,
  viewport: { width: 1400, height: 900 },
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
         '--disable-component-update', '--disable-sync', '--no-first-run'],
});
try {
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(url);
  await page.waitForFunction(() => document.getElementById('link-status').textContent === 'live',
                             null, { timeout: 15000 });
  fs.writeFileSync(path.join(dir, 'page-ready'), 'live\n');

  const controlPath = path.join(dir, 'control.json');
  for (let i = 0; i < 6000 && !fs.existsSync(controlPath); ++i) await sleep(100);
  const control = JSON.parse(fs.readFileSync(controlPath, 'utf8'));
  // The last frames are in flight for a few ms at most; give the page up to 2 s to show them.
  await page.waitForFunction((n) => document.getElementById('n-states').textContent === String(n),
                             control.num_delayed_states, { timeout: 2000 }).catch(() => {});
  const shown = await page.evaluate(() => ({
    depth_text: document.getElementById('depth').textContent,
    n_states_text: document.getElementById('n-states').textContent,
    n_links_text: document.getElementById('n-links').textContent,
    sensor_rows: [...document.querySelectorAll('#health-table tbody tr')].map((r) => r.dataset.sensor),
    row_classes: Object.fromEntries([...document.querySelectorAll('#health-table tbody tr')].map((r) => [r.dataset.sensor, r.className])),
    health_received_ms: window.topside.model.healthReceivedMs,
    health: window.topside.model.health,
  }));
  await page.screenshot({ path: path.join(dir, 'topside.png') });

  // Staleness: every sensor row's class 'stale' (or 'faulty'), timed from the last health message.
  const stale = await page.waitForFunction(() => {
    const rows = [...document.querySelectorAll('#health-table tbody tr')];
    return rows.length > 0 && rows.every((r) => r.className !== 'ok') ? Date.now() : false;
  }, null, { timeout: 10000, polling: 50 }).then((h) => h.jsonValue()).catch(() => null);
  const lastHealth = await page.evaluate(() => ({
    received_ms: window.topside.model.healthReceivedMs,
    newest_sensor_ms: window.topside.lastActivityMs() }));
  await page.screenshot({ path: path.join(dir, 'topside-stale.png') });
  const result = { ...shown, errors,
                   stale_after_last_health_ms: stale === null ? null : stale - lastHealth.received_ms,
                   stale_after_last_sensor_message_ms: stale === null ? null : stale - lastHealth.newest_sensor_ms };
  fs.writeFileSync(path.join(dir, 'result.json'), JSON.stringify(result, null, 1));
  console.log(JSON.stringify(result));
} finally {
  await context.close();
  fs.rmSync(userDataDir, { recursive: true, force: true });
}
