// What the browser tests share: playwright-core and Debian's chromium (or a skip), a logger with checks, and
// `deltagi serve` started on a free port.
import { spawn } from 'node:child_process';
import fs from 'node:fs';

export const SKIP = 77;

// playwright-core's chromium and the browser's path; exits with SKIP when either is missing.
export async function browserOrSkip() {
  let chromium;
  try {
    ({ chromium } = await import('playwright-core'));
  } catch {
    console.log('SKIP: playwright-core is not installed (scripts/install-deps.sh runs npm ci in tests/web)');
    process.exit(SKIP);
  }
  const executablePath = process.env.DELTAGI_CHROMIUM || '/usr/bin/chromium';
  if (!fs.existsSync(executablePath)) {
    console.log(`SKIP: no browser at ${executablePath} (scripts/install-deps.sh installs Debian's chromium)`);
    process.exit(SKIP);
  }
  return {
    // Headless chromium with `extraArgs`. Root (CI) cannot use chromium's sandbox; containers often give
    // /dev/shm 64 MB, too little for it.
    launch: (extraArgs = []) => chromium.launch({
      executablePath,
      headless: true,
      args: [...(process.getuid && process.getuid() === 0 ? ['--no-sandbox'] : []), '--disable-dev-shm-usage',
        ...extraArgs],
    }),
  };
}

export function logger() {
  const started = Date.now();
  const log = (text) => console.log(`[${((Date.now() - started) / 1000).toFixed(1)} s] ${text}`);
  const check = (condition, what) => {
    if (!condition) throw new Error(`FAILED: ${what}`);
    log(`ok: ${what}`);
  };
  return { log, check };
}

// `deltagi COMMAND...` that serves the page (`serve SCENE ...`, `live SCENE --serve ...`; --port 0 added):
// {server, url, exit (a promise of {code, signal}), stderr() (what it printed so far)}.
export async function startServer(deltagi, command, log) {
  const all = [...command, '--port', '0'];
  log(`${deltagi} ${all.join(' ')}`);
  const server = spawn(deltagi, all, { stdio: ['ignore', 'pipe', 'pipe'] });
  let stderr = '';
  server.stderr.on('data', (d) => { stderr += d; });
  const exit = new Promise((resolve) => server.on('exit', (code, signal) => resolve({ code, signal })));
  const url = await new Promise((resolve, reject) => {
    let text = '';
    const timer = setTimeout(() => reject(new Error(`no URL from deltagi serve in 120 s; stderr: ${stderr}`)), 120000);
    server.stdout.on('data', (d) => {
      text += d;
      const m = text.match(/http:\/\/\S+\//);
      if (m) { clearTimeout(timer); resolve(m[0]); }
    });
    server.on('exit', (code) => reject(new Error(`deltagi serve exited (${code}): ${stderr}`)));
  });
  log(`server at ${url}`);
  return { server, url, exit, stderr: () => stderr };
}

// Stops the server and reports: exit 1 with the failure, or 'passed'. A server that ended other than by the
// SIGTERM sent here is a failure too.
export async function finish(browser, serve, failed, log) {
  await browser.close();
  serve.server.kill('SIGTERM');
  const exit = await serve.exit;
  if (!failed && !(exit.code === 143 || exit.signal === 'SIGTERM'))
    failed = new Error(`deltagi serve ended with ${JSON.stringify(exit)}`);
  if (serve.stderr().trim()) console.log(`server stderr:\n${serve.stderr().trim()}`);
  if (failed) {
    console.log(String(failed.stack || failed));
    process.exit(1);
  }
  log('passed');
}
