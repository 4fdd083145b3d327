"""Every relative link in the Markdown files under a folder points at a file that exists there.
Usage: python3 check_links.py <prefix>/share/geohaz  (exit code 1 and the broken links otherwise)."""
import re
import sys
from pathlib import Path

root = Path(sys.argv[1])
link = re.compile(r"\]\(([^)\s]+)\)")
pages, links, broken = 0, 0, []
for md in sorted(root.rglob("*.md")):
    pages += 1
    for target in link.findall(md.read_text(encoding="utf-8")):
        if re.match(r"^[a-z]+:", target) or target.startswith("#"):
            continue
        links += 1
        if not (md.parent / target.split("#")[0]).exists():
            broken.append(f"{md.relative_to(root)}: {target}")
print(f"check_links: {pages} pages, {links} relative links, {len(broken)} broken")
for b in broken:
    print("  broken:", b)
sys.exit(1 if broken or pages < 10 or links < 20 else 0)
