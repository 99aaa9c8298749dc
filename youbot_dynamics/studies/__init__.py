"""The classic studies of the source documents, apart from the product: each runs its cases
and draws its figures with the documents' values beside ours. Nothing in the product
imports this package."""
