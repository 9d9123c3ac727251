"""Language families: the parts a family of controllers shares (lexer, expressions and variables, control
flow, calls, features and their code-table parts). ``fanuc`` is the Fanuc family's."""
