"""Packages are found, not listed: every folder with an ``__init__.py`` in the four trees ships.

The repository keeps the symbolic source, the generated code and the audit of the paper's text at
top level (``derivations/``, ``generated/``, ``audit/``); they install inside the one package,
``pfmdyn``.  Everything else is in ``pyproject.toml``.
"""
from setuptools import find_packages, setup

TREES = {"pfmdyn": "pfmdyn", "pfmdyn.derivations": "derivations",
         "pfmdyn.generated": "generated", "pfmdyn.audit": "audit"}

setup(
    package_dir=TREES,
    packages=[f"{name}{'.' + sub if sub else ''}" for name, folder in TREES.items()
              for sub in ["", *find_packages(folder)]],
    # the data the code reads at run time: recorded verdicts, codegen templates, errata, tables
    package_data={"": ["*.yaml", "*.json", "*.md", "templates/*.jinja"]},
)
