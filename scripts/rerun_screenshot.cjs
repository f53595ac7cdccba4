// Opens the Rerun web viewer at URL in headless Chromium, waits for the recording to load
// and draw, and saves a screenshot. Called by scripts/rerun_screenshot.sh.
//   node scripts/rerun_screenshot.cjs URL OUT.png SECONDS
// Needs playwright-core (npm install playwright-core; NODE_PATH pointing at its
// node_modules) and Debian's chromium.
const { chromium } = require("playwright-core");

async function main() {
  const [url, out, seconds] = process.argv.slice(2);
  const browser = await chromium.launch({
    executablePath: "/usr/bin/chromium",
    args: [
      "--no-sandbox",
      "--disable-gpu",
      "--disable-quic",
      "--no-first-run",
      "--disable-background-networking",
      "--disable-component-update",
      "--disable-sync",
    ],
  });
  const page = await browser.newPage({ viewport: { width: 1600, height: 900 } });
  await page.goto(url);
  await page.waitForTimeout(1000 * Number(seconds || 30));
  await page.screenshot({ path: out });
  await browser.close();
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
