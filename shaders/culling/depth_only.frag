// The depth pre-pass: depth only, no colour.
void main()
{
}
