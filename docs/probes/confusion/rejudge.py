"""Judge every recording confusion.py rendered (in $CONFUSION_DIR) again with the current code:
python rejudge.py after.json"""
import json, sys
from pathlib import Path
sys.path.insert(0, str(Path(__file__).parent))
from confusion import analyse, OUT

res = {mcap.stem: analyse(mcap) for mcap in sorted(OUT.glob("*.mcap"))}
Path(sys.argv[1]).write_text(json.dumps(res, indent=0))
