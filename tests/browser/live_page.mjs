// Opens propid's live page in Debian's Chromium (driven by playwright-core, no browser
// download), waits for live data, checks the charts and the running estimate, takes a
// screenshot, and presses STOP. Usage: node live_page.mjs URL [SCREENSHOT.png]
// Exit 0 when every check passed; the failing check is printed otherwise.
import { chromium } from "playwright-core";

const [url, shot] = process.argv.slice(2);
const browser = await chromium.launch({
  executablePath: "/usr/bin/chromium",
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 1500 } });
  await page.goto(url);
  // Live samples arrive over Server-Sent Events.
  await page.waitForFunction(() => Number(document.body.dataset.samples || 0) > 500, null, { timeout: 30000 });
  // The running estimate with its band: a number in the J cell.
  await page.waitForFunction(() => /^[0-9]/.test(document.getElementById("j").textContent), null, { timeout: 30000 });
  const charts = await page.locator("div.chart").count();
  const canvases = await page.locator("div.chart canvas").count();
  if (charts !== 5 || canvases !== charts) throw new Error(`charts ${charts}, canvases ${canvases}`);
  const readiness = await page.locator("#readiness").textContent();
  if (readiness !== "ENGAGED") throw new Error(`readiness ${readiness}`);
  if (shot) await page.screenshot({ path: shot, fullPage: false });
  await page.click("#stop");
  try {
    await page.waitForFunction(() => /STANDBY/.test(document.getElementById("status").textContent), null, { timeout: 15000 });
  } catch (e) {
    const status = await page.locator("#status").textContent();
    const finished = await page.evaluate(() => document.body.dataset.finished);
    throw new Error(`no STANDBY 15 s after STOP: status "${status}", finished ${finished}: ${e.message}`);
  }
  console.log("ok: live data, 5 charts, estimate shown, STOP pressed:", await page.locator("#status").textContent());
} finally {
  await browser.close();
}
