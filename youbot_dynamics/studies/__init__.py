"""The classic studies of the source documents, apart from the product.

Each study module runs its cases from a config (``run(config)``, with the text and JSON
``youbot-dynamics study NAME`` prints); its sibling ``<study>_figures.py`` draws the source
document's figures from our runs with the document's value beside ours
(studies/figures.py: the declared figure sets). catalog.py lists the report's sections
and report.py writes the page from them. Nothing in the product imports this package; the
command line (cli/) does.
"""
