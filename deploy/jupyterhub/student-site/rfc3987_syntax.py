"""Left out of the class members' servers and kernels (this folder is first on their PYTHONPATH).

The real package builds about forty Earley parsers when imported: 3.4 s of CPU on this
project's 2-core machine idle, paid by every Jupyter server at start (jupyter_events imports
jsonschema, whose format checkers import it if it is installed), so 100 s of CPU for a class of
thirty starting together. jsonschema treats it as optional: without it, only its ``iri`` and
``iri-reference`` format checks are skipped, which neither Jupyter's event schemas nor a lesson
use. The hub itself and everything outside the class's servers keep the real package.
"""

raise ImportError("rfc3987_syntax is left out of the class hub's servers (deploy/jupyterhub/student-site)")
