// Parses a .usda file with three.js's USDA parser (an independent reader of the text
// format, fetched by scripts/fetch-usda-parser.sh) and prints what it found as JSON:
// { "root": {upAxis, metersPerUnit, ...}, "specs": { "/path": {specType, fields} } }.
// Usage: node usda_check.mjs PARSER.js FILE.usda OUT.json
import { readFileSync, writeFileSync } from 'node:fs';
import { pathToFileURL } from 'node:url';

const [parserPath, file, out] = process.argv.slice(2);
if (!parserPath || !file || !out) {
  console.error('usage: node usda_check.mjs USDAParser.js FILE.usda OUT.json');
  process.exit(2);
}
const { USDAParser } = await import(pathToFileURL(parserPath).href);
const { specsByPath } = new USDAParser().parseData(readFileSync(file, 'utf8'));
writeFileSync(out, JSON.stringify({ root: specsByPath['/'].fields, specs: specsByPath }));
