#!/usr/bin/env python3
"""The facade's public API, counted from its rustdoc: every item page of the `pelage`
crate (structs, enums, functions, constants, statics, type aliases, traits) counts 1,
plus its inherent methods and associated constants, enum variants, public struct
fields and required trait methods. Re-exported crates (`pelage::scene`, ...) are their
own crates' pages and not counted; trait implementations (`Debug`, `From`, ...) are not
counted.

    cargo doc --no-deps -p pelage
    python3 scripts/api_count.py target/doc/pelage

Prints a line per item page and the total. Standard library only.
"""
import glob
import os
import re
import sys

KINDS = r"(struct|enum|fn|constant|static|type|trait|macro)\."


def count(directory):
    total, rows = 0, []
    for path in sorted(glob.glob(os.path.join(directory, "*.html"))):
        name = os.path.basename(path)
        if not re.match(KINDS, name):
            continue
        html = open(path, encoding="utf-8").read()
        # Inherent methods: the implementations list before the trait implementations.
        inherent = re.search(
            r'id="implementations-list"(.*?)(id="trait-implementations"|'
            r'id="synthetic-implementations"|id="blanket-implementations"|$)',
            html,
            re.S,
        )
        methods = (
            len(re.findall(r'id="(?:method|associatedconstant)\.', inherent.group(1)))
            if inherent
            else 0
        )
        variants = len(re.findall(r'id="variant\.[^."]*"', html))
        fields = len(re.findall(r'id="structfield\.[^."]*"', html))
        required = len(re.findall(r'id="tymethod\.', html))
        items = 1 + methods + variants + fields + required
        rows.append((name, methods, variants, fields, items))
        total += items
    return total, rows


def main():
    directory = sys.argv[1] if len(sys.argv) > 1 else "target/doc/pelage"
    if not os.path.isdir(directory):
        sys.exit(f"{directory}: no rustdoc output here; run `cargo doc --no-deps -p pelage` first")
    total, rows = count(directory)
    print(f"{'page':<32} {'methods':>7} {'variants':>8} {'fields':>6} {'items':>5}")
    for name, methods, variants, fields, items in rows:
        print(f"{name:<32} {methods:>7} {variants:>8} {fields:>6} {items:>5}")
    print(f"total: {total} items on {len(rows)} pages")


if __name__ == "__main__":
    main()
