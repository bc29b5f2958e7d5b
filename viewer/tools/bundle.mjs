// Bundles src/main.js (three.js included) into one minified script with esbuild's JS API
// (works whether or not npm ran esbuild's install script). Usage: node tools/bundle.mjs OUT.js
import { build } from 'esbuild';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const root = path.dirname(path.dirname(fileURLToPath(import.meta.url)));
const outfile = process.argv[2] || path.join(root, 'dist', 'viewer.js');
await build({
  entryPoints: [path.join(root, 'src', 'main.js')],
  bundle: true,
  minify: true,
  format: 'iife',
  target: ['es2020'],
  outfile,
  logLevel: 'warning',
});
