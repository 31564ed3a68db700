// Tokenizes a file with the TextMate grammar ../vfy.tmLanguage.json through vscode-textmate and the
// Oniguruma regular expressions VS Code uses; prints one JSON array of [line, start, end, text, scopes].
// Used by tests/test_textmate.py:  node editors/tmtest/tokenize.js FILE
const fs = require("fs");
const path = require("path");
const vsctm = require("vscode-textmate");
const oniguruma = require("vscode-oniguruma");

const wasm = fs.readFileSync(require.resolve("vscode-oniguruma/release/onig.wasm")).buffer;
const onigLib = oniguruma.loadWASM(wasm).then(() => ({
  createOnigScanner: (sources) => new oniguruma.OnigScanner(sources),
  createOnigString: (s) => new oniguruma.OnigString(s),
}));
const registry = new vsctm.Registry({
  onigLib,
  loadGrammar: async (scopeName) => {
    if (scopeName !== "source.vfy") return null;
    const file = path.join(__dirname, "..", "vfy.tmLanguage.json");
    return vsctm.parseRawGrammar(fs.readFileSync(file, "utf8"), file);
  },
});
registry.loadGrammar("source.vfy").then((grammar) => {
  const lines = fs.readFileSync(process.argv[2], "utf8").split("\n");
  const out = [];
  let state = vsctm.INITIAL;
  lines.forEach((line, i) => {
    const result = grammar.tokenizeLine(line, state);
    for (const t of result.tokens) {
      out.push([i + 1, t.startIndex, t.endIndex, line.substring(t.startIndex, t.endIndex), t.scopes]);
    }
    state = result.ruleStack;
  });
  process.stdout.write(JSON.stringify(out));
});
