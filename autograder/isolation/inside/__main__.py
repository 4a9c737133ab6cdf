"""Run the sandbox program: ``python -I -S -B <this file> --job FILE --site DIR --channel-fd N
--cases-fd M``.

``-I`` puts no script folder on ``sys.path``, so the folder holding this package is put there
just long enough to import it (the supervisor then cuts ``sys.path`` to the standard library
and the site dir).
"""

import os
import sys

if __name__ == "__main__":
    _HOME = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    sys.path.insert(0, _HOME)
    try:
        from inside.main import main
    finally:
        sys.path.remove(_HOME)
    main(sys.argv[1:])
